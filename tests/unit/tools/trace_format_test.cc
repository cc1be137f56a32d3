#include "trace_format.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "dpc/sim/trace_writer.h"

namespace dpc::tools {
namespace {

constexpr double kTolerance = 1e-15;

class TraceFormatTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_trace_format_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    path_ = (directory_ / "trace.csv").string();
    scenario_ = PaperScenario("131");
    scenario_.simulation.duration_s = 1e-4;
    scenario_.controller.activation_s = 3e-5;
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  // Writes a real trace of one row with the header comments of `simulator`.
  void WriteTrace(const ClosedLoopSimulator& simulator, int64_t trace_every) {
    std::vector<std::string> names;
    for (const auto& c : simulator.chain().controls()) names.push_back(c.name);
    TraceWriter writer(path_, names, TraceHeaderComments(simulator, trace_every));
    writer.Write(0.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0,
                 ControlVector::Zero(simulator.chain().control_count()));
  }

  std::filesystem::path directory_;
  std::string path_;
  ScenarioConfig scenario_;
};

TEST_F(TraceFormatTest, HeaderCommentsStartWithTheMagicLine) {
  const ClosedLoopSimulator simulator(scenario_);
  const std::vector<std::string> lines = TraceHeaderComments(simulator, 10);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "dpc-trace");
  EXPECT_EQ(lines[1], "title=paper-131: M = R1R3R1 (light: R1 R3 R1), gp, model loop");
  EXPECT_EQ(lines.back(), "trace_every=10");
}

TEST_F(TraceFormatTest, MetadataRoundTripsThroughATraceFile) {
  scenario_.controller.activation_s = 1.0 / 3.0 * 1e-4;  // needs all 17 digits
  scenario_.controller.loop = LoopMode::kMeasured;
  scenario_.controller.step = 0.02;
  const ClosedLoopSimulator simulator(scenario_);
  WriteTrace(simulator, 7);
  const std::map<std::string, std::string> metadata = ReadTraceMetadata(path_);
  EXPECT_EQ(metadata.size(), 5u);
  EXPECT_EQ(metadata.count("dpc-trace"), 0u);  // the magic line is not a key
  EXPECT_EQ(metadata.at("title"), "paper-131: M = R1R3R1 (light: R1 R3 R1), gp, measured loop");
  EXPECT_EQ(std::stod(metadata.at("activation_s")), scenario_.controller.activation_s);
  EXPECT_EQ(metadata.at("target_point"), "0,0.59999999999999998,0.80000000000000004");
  EXPECT_EQ(std::stod(metadata.at("sample_rate_hz")), 50e6);
  EXPECT_EQ(metadata.at("trace_every"), "7");
}

TEST_F(TraceFormatTest, FigureOptionsFromATraceEqualThoseOfItsRun) {
  const ClosedLoopSimulator simulator(scenario_);
  WriteTrace(simulator, 1);
  const FigureOptions direct = FigureOptionsFor(simulator);
  const FigureOptions read = FigureOptionsFromMetadata(ReadTraceMetadata(path_));
  EXPECT_EQ(read.title, direct.title);
  ASSERT_TRUE(read.activation_s.has_value());
  ASSERT_TRUE(direct.activation_s.has_value());
  EXPECT_EQ(*read.activation_s, *direct.activation_s);  // 17 digits: exact
  ASSERT_TRUE(read.target_point.has_value());
  ASSERT_TRUE(direct.target_point.has_value());
  EXPECT_EQ(*read.target_point, *direct.target_point);
}

TEST_F(TraceFormatTest, FigureOptionsForAPointTarget) {
  const ClosedLoopSimulator simulator(scenario_);
  const FigureOptions options = FigureOptionsFor(simulator);
  EXPECT_EQ(options.title, "paper-131: M = R1R3R1 (light: R1 R3 R1), gp, model loop");
  ASSERT_TRUE(options.activation_s.has_value());
  EXPECT_NEAR(*options.activation_s, 3e-5, kTolerance);
  ASSERT_TRUE(options.target_point.has_value());
  EXPECT_NEAR((*options.target_point - StokesVector(0, 0.6, 0.8)).norm(), 0.0, kTolerance);
}

TEST_F(TraceFormatTest, ASetTargetHasNoTargetPoint) {
  scenario_.target.kind = TargetConfig::Kind::kSet;
  scenario_.target.normal = Vector3::UnitZ();
  scenario_.target.offset = 0.5;
  const ClosedLoopSimulator simulator(scenario_);
  EXPECT_FALSE(FigureOptionsFor(simulator).target_point.has_value());
  WriteTrace(simulator, 1);
  const std::map<std::string, std::string> metadata = ReadTraceMetadata(path_);
  EXPECT_EQ(metadata.count("target_point"), 0u);
  EXPECT_FALSE(FigureOptionsFromMetadata(metadata).target_point.has_value());
}

TEST(FigureOptionsFromMetadataTest, ParsesTitleActivationAndTargetPoint) {
  const FigureOptions options = FigureOptionsFromMetadata(
      {{"title", "a, b"}, {"activation_s", "0.002"}, {"target_point", "0,0.6,0.8"},
       {"other", "ignored"}});
  EXPECT_EQ(options.title, "a, b");
  ASSERT_TRUE(options.activation_s.has_value());
  EXPECT_NEAR(*options.activation_s, 2e-3, kTolerance);
  ASSERT_TRUE(options.target_point.has_value());
  EXPECT_NEAR((*options.target_point - StokesVector(0, 0.6, 0.8)).norm(), 0.0, kTolerance);
}

TEST(FigureOptionsFromMetadataTest, MissingKeysStayUnset) {
  const FigureOptions options = FigureOptionsFromMetadata({});
  EXPECT_TRUE(options.title.empty());
  EXPECT_FALSE(options.activation_s.has_value());
  EXPECT_FALSE(options.target_point.has_value());
}

TEST(FigureOptionsFromMetadataTest, ATargetPointNeedsThreeComponents) {
  EXPECT_FALSE(FigureOptionsFromMetadata({{"target_point", "0,1"}}).target_point.has_value());
  EXPECT_FALSE(
      FigureOptionsFromMetadata({{"target_point", "0,0,1,0"}}).target_point.has_value());
}

TEST_F(TraceFormatTest, ATraceWithoutTheMagicLineIsRejectedByName) {
  { TraceWriter writer(path_, {"phi_1"}, {"title=not from dpc sim"}); }
  try {
    ReadTraceMetadata(path_);
    FAIL() << "a trace without '# dpc-trace' was read";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path_), std::string::npos) << message;
    EXPECT_NE(message.find("# dpc-trace"), std::string::npos) << message;
  }
}

TEST_F(TraceFormatTest, AMissingFileThrows) {
  EXPECT_THROW(ReadTraceMetadata((directory_ / "missing.csv").string()), std::runtime_error);
}

TEST_F(TraceFormatTest, AFileThatIsNotATraceThrows) {
  std::ofstream(path_) << "# dpc-trace\nnot,a,trace\n";
  EXPECT_THROW(ReadTraceMetadata(path_), std::runtime_error);
}

}  // namespace
}  // namespace dpc::tools
