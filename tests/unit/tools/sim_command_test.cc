#include "sim_command.h"

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dpc/scenario_io/scenario_reader.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

namespace fs = std::filesystem;

constexpr double kTolerance = 1e-15;

// Short runs: 50 000 samples (1 ms at 50 MHz), control from 0.2 ms (unless a test says
// otherwise).
const std::vector<std::pair<std::string, std::string>> kShortRun = {
    {"--duration-s", "1e-3"}, {"--activation-s", "2e-4"}};

class SimCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() /
                 ("dpc_sim_command_test_" +
                  std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(directory_);
    fs::create_directories(directory_);
    command_ = AddSimCommand(app_, &options_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  // Parses `dpc sim <args>`.
  void Parse(std::vector<std::string> args) {
    args.insert(args.begin(), {"dpc", "sim"});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    app_.parse(static_cast<int>(argv.size()), argv.data());
  }

  // Parses `dpc sim <args> <kShortRun>` and runs it, capturing stdout and stderr.
  cli::ExitCode Run(std::vector<std::string> args) {
    for (const auto& [flag, value] : kShortRun) {  // unless `args` gives its own value
      if (std::find(args.begin(), args.end(), flag) == args.end()) {
        args.insert(args.end(), {flag, value});
      }
    }
    args.push_back("--no-progress");
    Parse(args);
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    const cli::ExitCode code = RunSimCommand(options_);
    out_ = ::testing::internal::GetCapturedStdout();
    err_ = ::testing::internal::GetCapturedStderr();
    return code;
  }

  std::string PathIn(const std::string& name) const { return (directory_ / name).string(); }

  std::string WriteFile(const std::string& name, const std::string& text) const {
    std::ofstream(PathIn(name)) << text;
    return PathIn(name);
  }

  static std::string Slurp(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  static bool IsPng(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::array<char, 8> signature{};
    in.read(signature.data(), signature.size());
    return in.gcount() == 8 && std::string(signature.data() + 1, 3) == "PNG";
  }

  // Data rows of a trace (lines that are neither comments nor the header).
  static int DataRows(const std::string& path) {
    std::ifstream in(path);
    int rows = 0;
    for (std::string line; std::getline(in, line);) {
      rows += !line.empty() && line[0] != '#' && line.rfind("t_s,", 0) != 0;
    }
    return rows;
  }

  fs::path directory_;
  CLI::App app_{"dpc"};
  CLI::App* command_ = nullptr;
  SimOptions options_;
  std::string out_, err_;
};

TEST_F(SimCommandTest, ParsesEveryOption) {
  const std::string scenario = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/paper_fig4.pbtxt";
  Parse({scenario, "--trace", "t.csv", "--trace-every", "5", "--plot", "p.png", "--json",
         "--progress", "--no-progress", "--print-scenario", "--step", "0.3"});
  EXPECT_TRUE(command_->parsed());
  EXPECT_EQ(command_->get_name(), "sim");
  EXPECT_EQ(options_.scenario_path, scenario);
  EXPECT_EQ(options_.trace_path, "t.csv");
  EXPECT_EQ(options_.trace_every, 5);
  EXPECT_EQ(options_.plot_path, "p.png");
  EXPECT_TRUE(options_.json);
  EXPECT_TRUE(options_.progress);
  EXPECT_TRUE(options_.no_progress);
  EXPECT_TRUE(options_.print_scenario);
  ASSERT_TRUE(options_.overrides.step.has_value());  // the scenario override flags are there
  EXPECT_NEAR(*options_.overrides.step, 0.3, kTolerance);
}

TEST_F(SimCommandTest, DefaultsWithoutOptions) {
  Parse({});
  EXPECT_TRUE(options_.scenario_path.empty());
  EXPECT_TRUE(options_.trace_path.empty());
  EXPECT_EQ(options_.trace_every, 0);
  EXPECT_TRUE(options_.plot_path.empty());
  EXPECT_FALSE(options_.json);
  EXPECT_FALSE(options_.progress);
  EXPECT_FALSE(options_.no_progress);
  EXPECT_FALSE(options_.print_scenario);
}

TEST_F(SimCommandTest, ScenarioFileMustExist) {
  EXPECT_THROW(Parse({PathIn("missing.pbtxt")}), CLI::ValidationError);
}

TEST_F(SimCommandTest, TraceEveryMustBePositive) {
  EXPECT_THROW(Parse({"--trace-every", "0"}), CLI::ValidationError);
}

TEST_F(SimCommandTest, JsonPrintsOneParseableObject) {
  ASSERT_EQ(Run({"--json", "--seed", "3"}), cli::ExitCode::kOk) << err_;
  ASSERT_EQ(out_.find('\n'), out_.size() - 1) << "one line: " << out_;
  const nlohmann::json j = nlohmann::json::parse(out_);
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["samples"], 50000);
  EXPECT_EQ(j["seed"], 3);
  EXPECT_EQ(j["scenario"], "paper-131");
  EXPECT_FALSE(j["lock_time_s"].is_null());
  EXPECT_TRUE(j["warnings"].empty());
  EXPECT_TRUE(err_.empty()) << err_;
}

TEST_F(SimCommandTest, TextPrintsTheSummary) {
  ASSERT_EQ(Run({}), cli::ExitCode::kOk) << err_;
  EXPECT_EQ(out_.rfind("scenario   paper-131", 0), 0u) << out_;
  EXPECT_NE(out_.find("lock "), std::string::npos) << out_;
  EXPECT_NE(out_.find("50000 samples"), std::string::npos) << out_;
  EXPECT_EQ(out_.find("trace "), std::string::npos) << out_;
}

TEST_F(SimCommandTest, ScenarioFileIsRun) {
  const std::string path = WriteFile(
      "two.pbtxt", "name: \"two-stage\"\nstages { axis: S1 }\nstages { axis: S3 }\n");
  ASSERT_EQ(Run({path, "--json"}), cli::ExitCode::kOk) << err_;
  const nlohmann::json j = nlohmann::json::parse(out_);
  EXPECT_EQ(j["scenario"], "two-stage");
  EXPECT_EQ(j["controls"], 2);
}

TEST_F(SimCommandTest, WarningsGoToStderrAndTheJson) {
  ASSERT_EQ(Run({"--loop", "measured", "--json"}), cli::ExitCode::kOk) << err_;
  EXPECT_NE(err_.find("dpc sim: warning: "), std::string::npos) << err_;
  const nlohmann::json j = nlohmann::json::parse(out_);
  ASSERT_FALSE(j["warnings"].empty()) << out_;
  EXPECT_NE(err_.find(j["warnings"][0].get<std::string>()), std::string::npos) << err_;
}

TEST_F(SimCommandTest, TraceIsWrittenWithTheChosenDecimation) {
  const std::string trace = PathIn("run.csv");
  ASSERT_EQ(Run({"--trace", trace, "--trace-every", "100"}), cli::ExitCode::kOk) << err_;
  const std::string text = Slurp(trace);
  EXPECT_EQ(text.rfind("# dpc-trace\n", 0), 0u);
  EXPECT_NE(text.find("# trace_every=100\n"), std::string::npos);
  EXPECT_EQ(DataRows(trace), 500);
  EXPECT_NE(out_.find("trace      " + trace + " (500 rows, every 100 samples)"), std::string::npos)
      << out_;
}

TEST_F(SimCommandTest, TraceDecimationDefaultsToAboutFiftyThousandRows) {
  // 200 000 samples at 1 MHz: every 4th.
  const std::string trace = PathIn("run.csv");
  ASSERT_EQ(Run({"--trace", trace, "--sample-rate-hz", "1e6", "--duration-s", "0.2",
                 "--activation-s", "1e-3", "--rate-rad-per-s", "1e3"}),
            cli::ExitCode::kOk)
      << err_;
  EXPECT_NE(Slurp(trace).find("# trace_every=4\n"), std::string::npos);
  EXPECT_EQ(DataRows(trace), 50000);
}

TEST_F(SimCommandTest, PlotWritesAPngAndItsTraceNextToIt) {
  const std::string png = PathIn("fig.png");
  ASSERT_EQ(Run({"--plot", png}), cli::ExitCode::kOk) << err_;
  EXPECT_TRUE(IsPng(png));
  EXPECT_TRUE(fs::exists(directory_ / "fig.csv"));
  EXPECT_NE(out_.find("figure     " + png), std::string::npos) << out_;
}

TEST_F(SimCommandTest, PrintScenarioPrintsTheEffectiveScenarioAndRunsNothing) {
  ASSERT_EQ(Run({"--step", "0.3", "--print-scenario"}), cli::ExitCode::kOk) << err_;
  const ScenarioConfig printed = ScenarioFromProto(ParseScenarioText(out_, "<stdout>"));
  EXPECT_NEAR(printed.controller.step, 0.3, kTolerance);
  EXPECT_NEAR(printed.simulation.duration_s, 1e-3, kTolerance);
  EXPECT_EQ(out_.find("M samples/s"), std::string::npos) << "no run summary: " << out_;
}

TEST_F(SimCommandTest, AnInvalidFlagValueIsAnInvalidScenario) {
  EXPECT_EQ(Run({"--step", "-1", "--json"}), cli::ExitCode::kInvalidInput);
  EXPECT_NE(err_.find("dpc sim: invalid scenario: controller.step: "), std::string::npos) << err_;
  EXPECT_NE(err_.find("(set by --step)"), std::string::npos) << err_;
  EXPECT_TRUE(out_.empty()) << out_;
}

TEST_F(SimCommandTest, AnUnknownMethodIsAnInvalidScenario) {
  EXPECT_EQ(Run({"--method", "newton"}), cli::ExitCode::kInvalidInput);
  EXPECT_NE(err_.find("--method"), std::string::npos) << err_;
  EXPECT_TRUE(out_.empty()) << out_;
}

TEST_F(SimCommandTest, AnInvalidFileValueIsAnInvalidScenario) {
  const std::string path =
      WriteFile("bad.pbtxt", "stages { axis: S1 }\ncontroller { damping: -1 }\n");
  EXPECT_EQ(Run({path}), cli::ExitCode::kInvalidInput);
  EXPECT_NE(err_.find("controller.damping"), std::string::npos) << err_;
  EXPECT_EQ(err_.find("(set by"), std::string::npos) << err_;
}

TEST_F(SimCommandTest, ASyntaxErrorIsAnInvalidScenario) {
  const std::string path = WriteFile("syntax.pbtxt", "stages { axis: S1 ");
  EXPECT_EQ(Run({path}), cli::ExitCode::kInvalidInput);
  EXPECT_NE(err_.find(path + ":1:"), std::string::npos) << err_;
}

TEST_F(SimCommandTest, AnUnwritablePlotPathIsARuntimeError) {
  const std::string png = PathIn("missing_directory/fig.png");
  EXPECT_EQ(Run({"--plot", png, "--json"}), cli::ExitCode::kRuntimeError);
  EXPECT_NE(err_.find("missing_directory"), std::string::npos) << err_;
  EXPECT_TRUE(out_.empty()) << out_;
}

TEST_F(SimCommandTest, AnUnwritableTracePathIsARuntimeError) {
  EXPECT_EQ(Run({"--trace", PathIn("missing_directory/run.csv")}), cli::ExitCode::kRuntimeError);
  EXPECT_NE(err_.find("missing_directory/run.csv"), std::string::npos) << err_;
}

}  // namespace
}  // namespace dpc::tools
