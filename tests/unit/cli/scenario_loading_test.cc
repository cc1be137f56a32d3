#include "dpc/cli/scenario_loading.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "dpc/config/scenario_validation.h"

namespace dpc::cli {
namespace {

constexpr double kTolerance = 1e-15;

class ScenarioLoadingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_scenario_loading_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::string WriteScenario(const std::string& name, const std::string& text) {
    const std::string path = (directory_ / name).string();
    std::ofstream(path) << text;
    return path;
  }

  // The ScenarioError LoadScenarioWithOverrides throws, as DescribeScenarioError words it; ""
  // if it does not throw.
  std::string DescribedLoadError(const std::string& path) {
    try {
      LoadScenarioWithOverrides(path, overrides_, PaperScenario("131"));
    } catch (const ScenarioError& e) {
      return DescribeScenarioError(e, overrides_);
    }
    return "";
  }

  std::filesystem::path directory_;
  ScenarioOverrides overrides_;
};

TEST_F(ScenarioLoadingTest, EmptyPathGivesThePaperScenario) {
  const ScenarioConfig scenario = LoadScenarioWithOverrides("", overrides_, PaperScenario("131"));
  EXPECT_EQ(scenario.name, "paper-131");
  ASSERT_EQ(scenario.stages.size(), 3u);
  EXPECT_NEAR((scenario.stages[0].axis - Vector3::UnitX()).norm(), 0.0, kTolerance);
  EXPECT_NEAR((scenario.stages[1].axis - Vector3::UnitZ()).norm(), 0.0, kTolerance);
  EXPECT_NEAR((scenario.stages[2].axis - Vector3::UnitX()).norm(), 0.0, kTolerance);
  ASSERT_EQ(scenario.input.disturbances.size(), 1u);
  EXPECT_EQ(scenario.input.disturbances[0].kind, DisturbanceConfig::Kind::kPaperScrambler);
  EXPECT_NO_THROW(ValidateScenario(scenario));
}

TEST_F(ScenarioLoadingTest, OverridesApplyToThePaperScenario) {
  overrides_.step = 0.25;
  overrides_.stages_axes = "3131";
  const ScenarioConfig scenario = LoadScenarioWithOverrides("", overrides_, PaperScenario("131"));
  EXPECT_NEAR(scenario.controller.step, 0.25, kTolerance);
  EXPECT_EQ(scenario.stages.size(), 4u);
}

TEST_F(ScenarioLoadingTest, FilePathLoadsTheFile) {
  overrides_.duration_s = 1e-3;
  const ScenarioConfig scenario = LoadScenarioWithOverrides(
      std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/paper_fig4.pbtxt", overrides_, PaperScenario("131"));
  EXPECT_EQ(scenario.name, "paper-fig4");
  ASSERT_EQ(scenario.stages.size(), 4u);
  EXPECT_EQ(scenario.stages[0].name, "wp1");
  EXPECT_NEAR((scenario.stages[0].axis - Vector3::UnitZ()).norm(), 0.0, kTolerance);
  EXPECT_NEAR(scenario.simulation.duration_s, 1e-3, kTolerance);  // the flag wins over the file
  EXPECT_NEAR(scenario.simulation.sample_rate_hz, 50e6, kTolerance);  // the file's
}

TEST_F(ScenarioLoadingTest, FileValuesAreNotValidatedOnLoad) {
  const std::string path = WriteScenario(
      "bad_step.pbtxt", "name: \"bad\"\nstages { axis: S1 }\ncontroller { step: -1 }\n");
  ScenarioConfig scenario;
  ASSERT_NO_THROW(scenario = LoadScenarioWithOverrides(path, overrides_, PaperScenario("131")));
  EXPECT_EQ(scenario.name, "bad");
  EXPECT_NEAR(scenario.controller.step, -1.0, kTolerance);
  // It is caught later, when the scenario is validated.
  EXPECT_THROW(ValidateScenario(scenario), ScenarioError);
}

TEST_F(ScenarioLoadingTest, OverriddenValuesAreNotValidatedOnLoad) {
  overrides_.step = -2.0;
  ScenarioConfig scenario;
  ASSERT_NO_THROW(scenario = LoadScenarioWithOverrides("", overrides_, PaperScenario("131")));
  EXPECT_NEAR(scenario.controller.step, -2.0, kTolerance);
}

TEST_F(ScenarioLoadingTest, SyntaxErrorsThrowAtTheFilePosition) {
  const std::string path = WriteScenario("syntax.pbtxt", "stages { axis: S1 ");
  const std::string text = DescribedLoadError(path);
  EXPECT_EQ(text.rfind("invalid scenario: " + path + ":1:", 0), 0u) << text;
  EXPECT_EQ(text.find("(set by"), std::string::npos) << text;
}

TEST_F(ScenarioLoadingTest, MissingFileThrowsScenarioError) {
  EXPECT_THROW(LoadScenarioWithOverrides((directory_ / "missing.pbtxt").string(), overrides_, PaperScenario("131")),
               ScenarioError);
}

TEST_F(ScenarioLoadingTest, OverridesThatCannotBeStoredThrow) {
  overrides_.method = "newton";
  EXPECT_THROW(LoadScenarioWithOverrides("", overrides_, PaperScenario("131")), ScenarioError);
}

TEST_F(ScenarioLoadingTest, DescriptionNamesTheFlagThatSetTheField) {
  overrides_.step = -1.0;
  const ScenarioConfig scenario = LoadScenarioWithOverrides("", overrides_, PaperScenario("131"));
  try {
    ValidateScenario(scenario);
    FAIL() << "a negative step validated";
  } catch (const ScenarioError& e) {
    ASSERT_EQ(e.location(), "controller.step");
    EXPECT_EQ(DescribeScenarioError(e, overrides_),
              std::string("invalid scenario: ") + e.what() + " (set by --step)");
  }
}

TEST_F(ScenarioLoadingTest, DescriptionNamesTheFlagForAPathInsideTheField) {
  overrides_.stages_axes = "13";
  LoadScenarioWithOverrides("", overrides_, PaperScenario("131"));
  const ScenarioError error("stages[1].axis_vector", "zero-length axis");
  EXPECT_EQ(DescribeScenarioError(error, overrides_),
            "invalid scenario: stages[1].axis_vector: zero-length axis (set by --stages-axes)");
}

TEST_F(ScenarioLoadingTest, DescriptionOfAFieldNoFlagSetHasNoFlag) {
  overrides_.step = 0.2;
  LoadScenarioWithOverrides("", overrides_, PaperScenario("131"));
  const ScenarioError error("controller.damping", "-1 is negative");
  EXPECT_EQ(DescribeScenarioError(error, overrides_),
            "invalid scenario: controller.damping: -1 is negative");
}

TEST_F(ScenarioLoadingTest, DescriptionOfAFileValueHasNoFlag) {
  const std::string path =
      WriteScenario("bad_step.pbtxt", "stages { axis: S1 }\ncontroller { step: -1 }\n");
  const ScenarioConfig scenario = LoadScenarioWithOverrides(path, overrides_, PaperScenario("131"));
  try {
    ValidateScenario(scenario);
    FAIL() << "a negative step validated";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(DescribeScenarioError(e, overrides_), std::string("invalid scenario: ") + e.what());
  }
}

}  // namespace
}  // namespace dpc::cli
