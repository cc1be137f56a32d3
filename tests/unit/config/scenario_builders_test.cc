#include "dpc/config/scenario_builders.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

constexpr double kTight = 1e-15;

class ScenarioBuildersTest : public ::testing::Test {
 protected:
  static StageConfig AdjustableStage(bool retardance_controlled, bool orientation_controlled) {
    StageConfig stage;
    stage.kind = StageConfig::Kind::kAdjustableAxis;
    stage.name = "converter";
    stage.retardance.controlled = retardance_controlled;
    stage.retardance.fixed_rad = M_PI / 2;
    stage.orientation.controlled = orientation_controlled;
    stage.orientation.map.rad_per_unit = 2.0;
    stage.orientation.range = ControlRange{-3.0, 3.0};
    return stage;
  }

  ScenarioConfig scenario_ = PaperScenario("131");
};

TEST_F(ScenarioBuildersTest, LinearMap) {
  ControlMapConfig config;
  config.rad_per_unit = 2.0;
  config.offset_rad = 0.5;
  const ControlMap map = BuildControlMap(config);
  EXPECT_EQ(map.kind(), ControlMap::Kind::kLinear);
  EXPECT_NEAR(map.AngleRad(0.25), 1.0, kTight);
}

TEST_F(ScenarioBuildersTest, PolynomialMap) {
  ControlMapConfig config;
  config.kind = ControlMapConfig::Kind::kPolynomial;
  config.coefficients_rad = {0.1, 2.0, 0.5};
  const ControlMap map = BuildControlMap(config);
  EXPECT_EQ(map.kind(), ControlMap::Kind::kPolynomial);
  EXPECT_NEAR(map.AngleRad(2.0), 0.1 + 4.0 + 2.0, kTight);
}

TEST_F(ScenarioBuildersTest, TableMap) {
  ControlMapConfig config;
  config.kind = ControlMapConfig::Kind::kTable;
  config.table_control = {0.0, 1.0, 2.0};
  config.table_angle_rad = {0.0, 1.0, 3.0};
  const ControlMap map = BuildControlMap(config);
  EXPECT_EQ(map.kind(), ControlMap::Kind::kTable);
  EXPECT_NEAR(map.AngleRad(1.5), 2.0, kTight);
}

ControlMapConfig ByCondition(ControlMapConfig::Condition condition, double operating_point,
                             std::vector<ConditionTableConfig> tables) {
  ControlMapConfig config;
  config.kind = ControlMapConfig::Kind::kTablesByCondition;
  config.condition = condition;
  config.operating_point = operating_point;
  config.condition_tables = std::move(tables);
  return config;
}

TEST_F(ScenarioBuildersTest, TablesByTemperatureInterpolateLinearlyOverTheUnionOfTheirPoints) {
  const ControlMapConfig config = ByCondition(ControlMapConfig::Condition::kTemperatureC, 27.5,
                                              {{10.0, {0, 1, 2}, {0, 1, 3}},
                                               {20.0, {0, 2}, {0, 4}},
                                               {30.0, {0, 0.5, 2}, {0, 1, 5}}});
  const ControlMapConfig table = ResolveConditionTables(config);
  EXPECT_EQ(table.kind, ControlMapConfig::Kind::kTable);
  // Between the tables at 20 and 30 °C, 3/4 of the way: every control point of either.
  EXPECT_EQ(table.table_control, (std::vector<double>{0, 0.5, 2}));
  ASSERT_EQ(table.table_angle_rad.size(), 3u);
  EXPECT_NEAR(table.table_angle_rad[1], 0.25 * 1.0 + 0.75 * 1.0, kTight);
  EXPECT_NEAR(table.table_angle_rad[2], 0.25 * 4.0 + 0.75 * 5.0, kTight);
  const ControlMap map = BuildControlMap(config);
  EXPECT_EQ(map.kind(), ControlMap::Kind::kTable);
  EXPECT_NEAR(map.AngleRad(2.0), 4.75, kTight);
  // At a table's own condition: that table, exactly.
  const ControlMapConfig at_table = ResolveConditionTables(
      ByCondition(ControlMapConfig::Condition::kTemperatureC, 10.0, config.condition_tables));
  EXPECT_EQ(at_table.table_control, (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(at_table.table_angle_rad, (std::vector<double>{0, 1, 3}));
  // A union beyond one table's span: that table extrapolated linearly.
  const ControlMapConfig wider = ResolveConditionTables(ByCondition(
      ControlMapConfig::Condition::kTemperatureC, 15.0, {{10.0, {0, 1}, {0, 1}}, {20.0, {-1, 2}, {-2, 4}}}));
  EXPECT_EQ(wider.table_control, (std::vector<double>{-1, 0, 1, 2}));
  EXPECT_NEAR(wider.table_angle_rad[0], 0.5 * -1.0 + 0.5 * -2.0, kTight);
  EXPECT_NEAR(wider.table_angle_rad[3], 0.5 * 2.0 + 0.5 * 4.0, kTight);
}

TEST_F(ScenarioBuildersTest, TablesByWavelengthInterpolateInOneOverLambda) {
  // A retardance θ(φ)·λ0/λ at 1500 and 1600 nm: exact at 1550 nm in 1/λ (linear in λ is not).
  const auto at = [](double nm) { return std::vector<double>{0.0, 3.0 * 1550.0 / nm}; };
  const ControlMapConfig table = ResolveConditionTables(ByCondition(
      ControlMapConfig::Condition::kWavelengthNm, 1550.0, {{1500.0, {0, 1}, at(1500.0)}, {1600.0, {0, 1}, at(1600.0)}}));
  EXPECT_NEAR(table.table_angle_rad[1], 3.0, 1e-12);
  const double linear_in_lambda = 0.5 * (at(1500.0)[1] + at(1600.0)[1]);
  EXPECT_GT(std::abs(linear_in_lambda - 3.0), 1e-3);
}

TEST_F(ScenarioBuildersTest, TablesByConditionRefuseAPointOutsideTheirSpan) {
  const ControlMapConfig config = ByCondition(ControlMapConfig::Condition::kTemperatureC, 41.0,
                                              {{20.0, {0, 1}, {0, 1}}, {40.0, {0, 1}, {0, 1.1}}});
  try {
    ResolveConditionTables(config);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "the operating point 41 °C is outside the calibrated 20–40 °C (a calibration is not extrapolated: "
                 "calibrate there too)");
  }
  EXPECT_THROW(BuildControlMap(config), std::invalid_argument);
  EXPECT_THROW(ResolveConditionTables(ByCondition(ControlMapConfig::Condition::kTemperatureC, 20.0,
                                                  {{20.0, {0, 1}, {0, 1}}})),
               std::invalid_argument);
}

TEST_F(ScenarioBuildersTest, BadMapThrowsInvalidArgument) {
  ControlMapConfig config;
  config.rad_per_unit = 0.0;
  EXPECT_THROW(BuildControlMap(config), std::invalid_argument);
}

TEST_F(ScenarioBuildersTest, PaperChainMatchesFromAxes) {
  const WaveplateChain chain = BuildChain(scenario_.stages);
  const WaveplateChain reference = WaveplateChain::FromAxes("131");
  EXPECT_EQ(chain.Describe(), reference.Describe());
  ASSERT_EQ(chain.control_count(), 3);
  ControlVector phi(3);
  phi << 0.3, -0.7, 1.1;
  const StokesVector s_in = StokesVector(0.48, 0.6, 0.64);
  EXPECT_LT((chain.Output(phi, s_in) - reference.Output(phi, s_in)).norm(), kTight);
}

TEST_F(ScenarioBuildersTest, FixedAxisStageKeepsMapRangeAndName) {
  scenario_.stages[1].axis = Vector3(0.0, 3.0, 4.0);
  scenario_.stages[1].range = ControlRange{-1.5, 2.5};
  scenario_.stages[1].name = "middle";
  scenario_.stages[1].map.rad_per_unit = 2.0;
  const WaveplateChain chain = BuildChain(scenario_.stages);
  const WaveplateStage& stage = chain.stages()[1];
  EXPECT_EQ(stage.kind(), WaveplateStage::Kind::kFixedAxis);
  EXPECT_EQ(stage.name(), "middle");
  EXPECT_LT((stage.axis() - Vector3(0.0, 0.6, 0.8)).norm(), kTight);
  ASSERT_EQ(stage.controls().size(), 1u);
  ASSERT_TRUE(stage.controls()[0].range.has_value());
  EXPECT_EQ(stage.controls()[0].range->min, -1.5);
  EXPECT_EQ(stage.controls()[0].range->max, 2.5);
  EXPECT_NEAR(stage.controls()[0].map.linear_rad_per_unit(), 2.0, kTight);
}

TEST_F(ScenarioBuildersTest, AdjustableAxisStagesBuildFixedAndControlledAngles) {
  scenario_.stages = {AdjustableStage(false, true), AdjustableStage(true, true)};
  const WaveplateChain chain = BuildChain(scenario_.stages);
  ASSERT_EQ(chain.stage_count(), 2);
  EXPECT_EQ(chain.control_count(), 3);
  const WaveplateStage& quarter_wave = chain.stages()[0];
  EXPECT_EQ(quarter_wave.kind(), WaveplateStage::Kind::kAdjustableAxis);
  EXPECT_EQ(quarter_wave.name(), "converter");
  EXPECT_FALSE(quarter_wave.retardance().control.has_value());
  EXPECT_NEAR(quarter_wave.retardance().fixed_angle_rad, M_PI / 2, kTight);
  ASSERT_TRUE(quarter_wave.orientation().control.has_value());
  EXPECT_NEAR(quarter_wave.orientation().control->map.linear_rad_per_unit(), 2.0, kTight);
  ASSERT_TRUE(quarter_wave.orientation().control->range.has_value());
  EXPECT_EQ(quarter_wave.orientation().control->range->max, 3.0);
  EXPECT_TRUE(chain.stages()[1].retardance().control.has_value());
}

TEST_F(ScenarioBuildersTest, BadStageThrowsLocatedError) {
  scenario_.stages[1].axis = Vector3::Zero();
  EXPECT_THROW(BuildChain(scenario_.stages), ScenarioError);
  try {
    BuildChain(scenario_.stages);
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location(), "stages[1]");
  }
}

TEST_F(ScenarioBuildersTest, EmptyChainThrowsLocatedError) {
  EXPECT_THROW(BuildChain({}), ScenarioError);
  try {
    BuildChain({});
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location(), "stages");
  }
}

TEST_F(ScenarioBuildersTest, PointTarget) {
  const Target target = BuildTarget(scenario_.target);
  EXPECT_TRUE(target.is_point());
  EXPECT_LT((target.point() - StokesVector(0.0, 0.6, 0.8)).norm(), kTight);
}

TEST_F(ScenarioBuildersTest, SetTargetIsNormalized) {
  TargetConfig config;
  config.kind = TargetConfig::Kind::kSet;
  config.normal = Vector3(0.0, 0.0, 2.0);
  config.offset = 1.0;
  const Target target = BuildTarget(config);
  EXPECT_EQ(target.kind(), Target::Kind::kSet);
  EXPECT_LT((target.normal() - Vector3::UnitZ()).norm(), kTight);
  EXPECT_NEAR(target.offset(), 0.5, kTight);
}

TEST_F(ScenarioBuildersTest, BadTargetThrowsLocatedError) {
  scenario_.target.point = StokesVector(0.0, 0.0, 0.5);
  EXPECT_THROW(BuildTarget(scenario_.target), ScenarioError);
  try {
    BuildTarget(scenario_.target);
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location(), "target.point");
  }
}

TEST_F(ScenarioBuildersTest, LawTimingIsTheSampleRateAndTheLoopDelayInSamples) {
  const LawTiming timing = BuildLawTiming(scenario_.simulation);
  EXPECT_EQ(timing.sample_rate_hz, 50e6);
  EXPECT_EQ(timing.delay_samples, 50);
}

TEST_F(ScenarioBuildersTest, EveryMethodOfAValidScenarioBuildsALaw) {
  for (ControlMethod method :
       {ControlMethod::kInverse, ControlMethod::kTranspose, ControlMethod::kDamped,
        ControlMethod::kPseudoInverse, ControlMethod::kRegularizedLeastSquares,
        ControlMethod::kGradientProjection, ControlMethod::kThresholdedGradientProjection,
        ControlMethod::kExtendedJacobian, ControlMethod::kDither}) {
    SCOPED_TRACE(std::string(MethodName(method)));
    scenario_.controller.method = method;
    ASSERT_NO_THROW(ValidateScenario(scenario_));
    EXPECT_NE(MakeControlLaw(scenario_.controller, BuildLawTiming(scenario_.simulation),
                             ScenarioControlCount(scenario_.stages), true),
              nullptr);
  }
}

TEST_F(ScenarioBuildersTest, InitialPhiIsZeroWhenEmpty) {
  const ControlVector phi = BuildInitialPhi(scenario_.controller, 3);
  ASSERT_EQ(phi.size(), 3);
  EXPECT_EQ(phi.norm(), 0.0);
}

TEST_F(ScenarioBuildersTest, InitialPhiIsCopied) {
  scenario_.controller.initial_phi = {0.1, -0.2, 0.3};
  const ControlVector phi = BuildInitialPhi(scenario_.controller, 3);
  ASSERT_EQ(phi.size(), 3);
  EXPECT_EQ(phi[0], 0.1);
  EXPECT_EQ(phi[1], -0.2);
  EXPECT_EQ(phi[2], 0.3);
}

TEST_F(ScenarioBuildersTest, InitialPhiOfTheWrongSizeThrows) {
  scenario_.controller.initial_phi = {0.1, -0.2};
  EXPECT_THROW(BuildInitialPhi(scenario_.controller, 3), ScenarioError);
}

TEST_F(ScenarioBuildersTest, InitialPhiBeyondTheControlCapacityThrows) {
  EXPECT_THROW(BuildInitialPhi(scenario_.controller, kMaxControls + 1), ScenarioError);
  EXPECT_THROW(BuildInitialPhi(scenario_.controller, -1), ScenarioError);
}

}  // namespace
}  // namespace dpc
