// The services' shared runtime: common options, the scenario (embedded default, file,
// override flags), error descriptions, logging and the rate-limited rejection log.
#include "service_runtime.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "dpc/config/scenario_validation.h"

namespace dpc::services {
namespace {

constexpr double kTolerance = 1e-15;

class ServiceRuntimeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_service_runtime_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    AddCommonOptions(app_, &options_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::string WriteScenario(const std::string& text) {
    const std::string path = (directory_ / "scenario.pbtxt").string();
    std::ofstream(path) << text;
    return path;
  }

  /// DescribeError's text for the scenario the options load, or "" if it validates.
  std::string DescribedValidationError() {
    const ScenarioConfig scenario = LoadServiceScenario(options_);
    try {
      ValidateScenario(scenario);
    } catch (const ScenarioError& e) {
      return DescribeError(e, options_);
    }
    return "";
  }

  std::filesystem::path directory_;
  CLI::App app_{"service runtime test"};
  CommonOptions options_;
};

TEST_F(ServiceRuntimeTest, WithoutAFileLoadsTheEmbeddedBenchScenario) {
  const ScenarioConfig scenario = LoadServiceScenario(options_);
  EXPECT_EQ(scenario.name, "bench-default");
  ASSERT_EQ(scenario.stages.size(), 3u);
  EXPECT_EQ(scenario.stages[0].name, "wp1");
  EXPECT_NEAR((scenario.stages[1].axis - Vector3::UnitZ()).norm(), 0.0, kTolerance);
  EXPECT_NEAR(scenario.controller.step, 0.5, kTolerance);
  EXPECT_NEAR(scenario.simulation.sample_rate_hz, 10e3, kTolerance);
  EXPECT_NO_THROW(ValidateScenario(scenario));
  EXPECT_NE(std::string(DefaultBenchScenarioText()).find("name: \"bench-default\""), std::string::npos);
}

TEST_F(ServiceRuntimeTest, APositionalFileReplacesTheEmbeddedScenario) {
  const std::string path = WriteScenario(
      "name: \"from-file\"\n"
      "stages { axis: S3 map { linear { rad_per_unit: 3.141592653589793 } } }\n"
      "stages { axis: S1 map { linear { rad_per_unit: 3.141592653589793 } } }\n"
      "controller { step: 0.25 }\n");
  app_.parse(path, false);
  EXPECT_EQ(options_.scenario_file, path);
  const ScenarioConfig scenario = LoadServiceScenario(options_);
  EXPECT_EQ(scenario.name, "from-file");
  ASSERT_EQ(scenario.stages.size(), 2u);
  EXPECT_NEAR((scenario.stages[0].axis - Vector3::UnitZ()).norm(), 0.0, kTolerance);
  EXPECT_NEAR(scenario.controller.step, 0.25, kTolerance);
}

TEST_F(ServiceRuntimeTest, AnotherEmbeddedDefaultStandsInForTheFileWithTheOverridesApplied) {
  constexpr const char* kDefault =
      "name: \"own-default\"\n"
      "stages { axis: S1 map { polynomial { coefficients_rad: [ 0, 0.62, 0, 3e-4 ] } } }\n";
  app_.parse("--noise-deg 0.25", false);
  const ScenarioConfig scenario = LoadServiceScenario(options_, kDefault, "<own.pbtxt>");
  EXPECT_EQ(scenario.name, "own-default");
  ASSERT_EQ(scenario.stages.size(), 1u);
  EXPECT_EQ(scenario.stages[0].map.coefficients_rad, (std::vector<double>{0, 0.62, 0, 3e-4}));
  EXPECT_NEAR(scenario.simulation.polarimeter_noise_deg, 0.25, kTolerance);
  try {
    LoadServiceScenario(options_, "stages { axis: S7 }", "<own.pbtxt>");
    FAIL() << "a bad default was parsed";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location().rfind("<own.pbtxt>:1:", 0), 0u) << e.what();
  }
  // A file still wins over the default.
  const std::string path = WriteScenario("name: \"from-file\"\nstages { axis: S3 }\n");
  app_.parse(path, false);
  EXPECT_EQ(LoadServiceScenario(options_, kDefault, "<own.pbtxt>").name, "from-file");
}

TEST_F(ServiceRuntimeTest, AMissingFileIsRefusedByTheCommandLine) {
  EXPECT_THROW(app_.parse((directory_ / "missing.pbtxt").string(), false), CLI::ValidationError);
}

TEST_F(ServiceRuntimeTest, OverrideFlagsApplyToTheEmbeddedScenario) {
  app_.parse("--step 0.125 --seed 7 --duration-s 0.5", false);
  const ScenarioConfig scenario = LoadServiceScenario(options_);
  EXPECT_EQ(scenario.name, "bench-default");
  EXPECT_NEAR(scenario.controller.step, 0.125, kTolerance);
  EXPECT_EQ(scenario.simulation.seed, 7u);
  EXPECT_NEAR(scenario.simulation.duration_s, 0.5, kTolerance);
}

TEST_F(ServiceRuntimeTest, OverrideFlagsWinOverTheFile) {
  const std::string path = WriteScenario(
      "name: \"from-file\"\n"
      "stages { axis: S1 map { linear { rad_per_unit: 3.141592653589793 } } }\n"
      "controller { step: 0.25 }\n");
  app_.parse(path + " --step 0.75", false);
  const ScenarioConfig scenario = LoadServiceScenario(options_);
  EXPECT_EQ(scenario.name, "from-file");
  EXPECT_NEAR(scenario.controller.step, 0.75, kTolerance);
}

TEST_F(ServiceRuntimeTest, CommonOptionsHaveTheirDefaultsAndParse) {
  EXPECT_EQ(options_.domain_id, 0);
  EXPECT_EQ(options_.bench_id, "bench1");
  EXPECT_EQ(options_.log_level, "info");
  app_.parse("--domain 66 --bench-id lab2 --log-level warn", false);
  EXPECT_EQ(options_.domain_id, 66);
  EXPECT_EQ(options_.bench_id, "lab2");
  EXPECT_EQ(options_.log_level, "warn");
}

TEST_F(ServiceRuntimeTest, CommonOptionsRefuseValuesOutOfTheirRange) {
  EXPECT_THROW(app_.parse("--domain 233", false), CLI::ValidationError);
  EXPECT_THROW(app_.parse("--bench-id " + std::string(64, 'b'), false), CLI::ValidationError);
  EXPECT_THROW(app_.parse("--log-level verbose", false), CLI::ValidationError);
}

TEST_F(ServiceRuntimeTest, DescribeErrorNamesTheFlagThatSetTheBadField) {
  app_.parse("--step=-1", false);
  const std::string text = DescribedValidationError();
  EXPECT_EQ(text.rfind("invalid scenario: controller.step: ", 0), 0u) << text;
  EXPECT_NE(text.find("(set by --step)"), std::string::npos) << text;
}

TEST_F(ServiceRuntimeTest, DescribeErrorOfAFileValueNamesNoFlag) {
  const std::string path = WriteScenario(
      "stages { axis: S1 map { linear { rad_per_unit: 3.141592653589793 } } }\n"
      "controller { step: -1 }\n");
  app_.parse(path + " --seed 3", false);
  const std::string text = DescribedValidationError();
  EXPECT_EQ(text.rfind("invalid scenario: controller.step: ", 0), 0u) << text;
  EXPECT_EQ(text.find("(set by"), std::string::npos) << text;
}

// Installs a logger that writes "level: message" lines into a string as the default logger, and
// puts the previous default logger back when it goes.
class CapturedLog {
 public:
  CapturedLog() : previous_(spdlog::default_logger()) {
    auto logger = std::make_shared<spdlog::logger>(
        "service_runtime_test", std::make_shared<spdlog::sinks::ostream_sink_mt>(stream_));
    logger->set_pattern("%l: %v");
    spdlog::set_default_logger(logger);
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }

  std::vector<std::string> Lines() const {
    std::vector<std::string> lines;
    std::istringstream in(stream_.str());
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }

 private:
  std::ostringstream stream_;
  std::shared_ptr<spdlog::logger> previous_;
};

TEST(RejectionLog, LogsTheFirstRejectionThenOneLinePerThousand) {
  CapturedLog log;
  RejectionLog rejections("rejected sample");
  rejections.Update(0, "");                      // nothing rejected yet
  rejections.Update(1, "s_in is not a unit Stokes vector");
  rejections.Update(1, "s_in is not a unit Stokes vector");  // no new rejection
  rejections.Update(500, "late");
  rejections.Update(999, "late");
  rejections.Update(1000, "sequence_number 0");  // crosses 1 × kEvery
  rejections.Update(1999, "late");
  rejections.Update(3500, "stale");              // crosses 2 × and 3 × kEvery: one line
  EXPECT_EQ(log.Lines(), (std::vector<std::string>{
                             "warning: rejected sample #1: s_in is not a unit Stokes vector",
                             "warning: rejected sample #1000: sequence_number 0",
                             "warning: rejected sample #3500: stale",
                         }));
}

TEST(RejectionLog, ABurstBeforeTheFirstUpdateIsReportedOnce) {
  CapturedLog log;
  RejectionLog rejections("rejected command");
  rejections.Update(RejectionLog::kEvery + 5, "unknown controller");
  rejections.Update(RejectionLog::kEvery + 6, "unknown controller");
  EXPECT_EQ(log.Lines(), (std::vector<std::string>{
                             "warning: rejected command #1005: unknown controller",
                         }));
}

// SetUpLogging replaces the default logger; the fixture puts the test's own one back.
class SetUpLoggingTest : public ::testing::Test {
 protected:
  void SetUp() override { previous_ = spdlog::default_logger(); }
  void TearDown() override {
    spdlog::set_default_logger(previous_);
    spdlog::drop("polarimeter");
  }
  std::shared_ptr<spdlog::logger> previous_;
};

TEST_F(SetUpLoggingTest, TwiceWithTheSameNameDoesNotThrowAndTheSecondWins) {
  CommonOptions options;
  options.bench_id = "lab7";
  EXPECT_NO_THROW(SetUpLogging("polarimeter", options));
  options.log_level = "warn";
  EXPECT_NO_THROW(SetUpLogging("polarimeter", options));
  EXPECT_EQ(spdlog::default_logger()->name(), "polarimeter");
  EXPECT_EQ(spdlog::default_logger()->level(), spdlog::level::warn);
}

TEST_F(SetUpLoggingTest, LinesOnStderrNameTheServiceAndTheBench) {
  CommonOptions options;
  options.bench_id = "lab7";
  SetUpLogging("polarimeter", options);
  ::testing::internal::CaptureStderr();
  spdlog::info("started");
  spdlog::debug("below the level");
  const std::string text = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(text.find("[polarimeter lab7] info: started"), std::string::npos) << text;
  EXPECT_EQ(text.find("below the level"), std::string::npos) << text;
}

}  // namespace
}  // namespace dpc::services
