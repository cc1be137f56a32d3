#include "dpc/config/scenario_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

constexpr double kExact = 0.0;

TEST(ScenarioConfigTest, StagesFromAxesMapsDigitsToElementalAxes) {
  const std::vector<StageConfig> stages = StagesFromAxes("1231");
  ASSERT_EQ(stages.size(), 4u);
  EXPECT_EQ(stages[0].axis, Vector3::UnitX());
  EXPECT_EQ(stages[1].axis, Vector3::UnitY());
  EXPECT_EQ(stages[2].axis, Vector3::UnitZ());
  EXPECT_EQ(stages[3].axis, Vector3::UnitX());
  for (const StageConfig& stage : stages) {
    EXPECT_EQ(stage.kind, StageConfig::Kind::kFixedAxis);
    EXPECT_EQ(stage.map.kind, ControlMapConfig::Kind::kLinear);
    EXPECT_NEAR(stage.map.rad_per_unit, M_PI, kExact);
    EXPECT_NEAR(stage.map.offset_rad, 0.0, kExact);
    EXPECT_FALSE(stage.range.has_value());
  }
}

TEST(ScenarioConfigTest, StagesFromAxesOfNothingIsEmpty) {
  EXPECT_TRUE(StagesFromAxes("").empty());
}

TEST(ScenarioConfigTest, StagesFromAxesRejectsOtherCharacters) {
  EXPECT_THROW(StagesFromAxes("14"), std::invalid_argument);
  EXPECT_THROW(StagesFromAxes("1 3"), std::invalid_argument);
}

TEST(ScenarioConfigTest, PaperScenarioIsSectionFour) {
  const ScenarioConfig scenario = PaperScenario("131");
  EXPECT_EQ(scenario.name, "paper-131");
  ASSERT_EQ(scenario.stages.size(), 3u);
  EXPECT_EQ(scenario.stages[0].axis, Vector3::UnitX());
  EXPECT_EQ(scenario.stages[1].axis, Vector3::UnitZ());
  EXPECT_EQ(scenario.stages[2].axis, Vector3::UnitX());

  EXPECT_EQ(scenario.input.initial_sop, StokesVector::UnitX());
  ASSERT_EQ(scenario.input.disturbances.size(), 1u);
  const DisturbanceConfig& scrambler = scenario.input.disturbances[0];
  EXPECT_EQ(scrambler.kind, DisturbanceConfig::Kind::kPaperScrambler);
  EXPECT_NEAR(scrambler.rate_rad_per_s, 1e5, kExact);
  EXPECT_EQ(scrambler.axis, Vector3::UnitZ());
  EXPECT_EQ(scrambler.kick_axis, Vector3::UnitY());
  EXPECT_NEAR(scrambler.kick_rms_ratio, 1.0, kExact);

  EXPECT_EQ(scenario.target.kind, TargetConfig::Kind::kPoint);
  EXPECT_LT((scenario.target.point - StokesVector(0.0, 0.6, 0.8)).norm(), 1e-15);

  EXPECT_EQ(scenario.controller.method, ControlMethod::kGradientProjection);
  EXPECT_NEAR(scenario.controller.step, 0.1, kExact);
  EXPECT_NEAR(scenario.controller.activation_s, 2e-3, kExact);
  EXPECT_TRUE(scenario.controller.initial_phi.empty());

  EXPECT_NEAR(scenario.simulation.sample_rate_hz, 50e6, kExact);
  EXPECT_NEAR(scenario.simulation.delay_s, 1e-6, kExact);
  EXPECT_EQ(DelaySamples(scenario.simulation), 50);
}

TEST(ScenarioConfigTest, PaperScenarioIsValidForEveryPaperDevice) {
  for (const char* axes : {"131", "3131", "1", "13"}) {
    SCOPED_TRACE(axes);
    const ScenarioConfig scenario = PaperScenario(axes);
    EXPECT_EQ(scenario.stages.size(), std::string(axes).size());
    EXPECT_NO_THROW(ValidateScenario(scenario));
  }
}

TEST(ScenarioConfigTest, PaperScenarioRejectsBadAxes) {
  EXPECT_THROW(PaperScenario("1x1"), std::invalid_argument);
}

TEST(ScenarioConfigTest, DefaultScenarioHasNoStages) {
  // The defaults describe everything but the device: validation must ask for stages.
  const ScenarioConfig scenario;
  EXPECT_TRUE(scenario.stages.empty());
  EXPECT_THROW(ValidateScenario(scenario), ScenarioError);
}

}  // namespace
}  // namespace dpc
