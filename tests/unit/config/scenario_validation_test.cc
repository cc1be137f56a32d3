#include "dpc/config/scenario_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace dpc {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Starts from the paper's valid scenario; each test breaks one field and checks the path.
class ScenarioValidationTest : public ::testing::Test {
 protected:
  /// The error ValidateScenario reports, or nullopt if it accepts the scenario.
  std::optional<ScenarioError> Error() const {
    try {
      ValidateScenario(scenario_);
    } catch (const ScenarioError& e) {
      return e;
    }
    return std::nullopt;
  }
  /// The location of the error, or "(valid)".
  std::string ErrorLocation() const {
    const auto error = Error();
    return error ? error->location() : "(valid)";
  }
  std::string ErrorMessage() const {
    const auto error = Error();
    return error ? error->message() : "(valid)";
  }

  static ControlMapConfig Table(std::vector<double> control, std::vector<double> angle_rad) {
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kTable;
    map.table_control = std::move(control);
    map.table_angle_rad = std::move(angle_rad);
    return map;
  }
  static ControlMapConfig Polynomial(std::vector<double> coefficients_rad) {
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kPolynomial;
    map.coefficients_rad = std::move(coefficients_rad);
    return map;
  }
  /// A rotatable quarter-wave plate: θ fixed at π/2, ϕ controlled.
  static StageConfig QuarterWavePlate() {
    StageConfig stage;
    stage.kind = StageConfig::Kind::kAdjustableAxis;
    stage.retardance.fixed_rad = M_PI / 2;
    stage.orientation.controlled = true;
    return stage;
  }
  DisturbanceConfig& Scrambler() { return scenario_.input.disturbances[0]; }

  ScenarioConfig scenario_ = PaperScenario("131");
};

TEST_F(ScenarioValidationTest, PaperScenarioIsValid) {
  EXPECT_NO_THROW(ValidateScenario(scenario_));
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, ErrorSaysWhatIsWrongAndWhatIsExpected) {
  scenario_.controller.step = -0.1;
  EXPECT_THROW(ValidateScenario(scenario_), ScenarioError);
  EXPECT_EQ(ErrorLocation(), "controller.step");
  EXPECT_EQ(ErrorMessage(),
            "-0.1 is not > 0; the task step must be positive (typical 0.01 to 1)");
  const auto error = Error();
  ASSERT_TRUE(error);
  EXPECT_STREQ(error->what(),
               "controller.step: -0.1 is not > 0; the task step must be positive (typical 0.01 "
               "to 1)");
}

// ---- Stages.

TEST_F(ScenarioValidationTest, ZeroStagesAreRejected) {
  scenario_.stages.clear();
  EXPECT_EQ(ErrorLocation(), "stages");
  EXPECT_EQ(ErrorMessage(), "0 stages; a chain needs 1 to 16");
}

TEST_F(ScenarioValidationTest, SeventeenStagesAreRejected) {
  scenario_.stages = StagesFromAxes("13131313131313131");
  scenario_.controller.method = ControlMethod::kPseudoInverse;
  EXPECT_EQ(ErrorLocation(), "stages");
  EXPECT_THAT(ErrorMessage(), HasSubstr("17 stages"));
}

TEST_F(ScenarioValidationTest, SixteenStagesOfTwoControlsAreTheLimit) {
  StageConfig both = QuarterWavePlate();
  both.retardance.controlled = true;
  scenario_.stages.assign(16, both);
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), kMaxControls);
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, ZeroLengthAxisIsRejected) {
  scenario_.stages[2].axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "stages[2].axis_vector");
  EXPECT_THAT(ErrorMessage(), HasSubstr("zero-length axis"));
}

TEST_F(ScenarioValidationTest, AnyNonZeroAxisIsAccepted) {
  scenario_.stages[2].axis = Vector3(0.0, 3.0, 4.0);
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, NonFiniteAxisComponentIsNamed) {
  scenario_.stages[1].axis = Vector3(0.0, kInf, 1.0);
  EXPECT_EQ(ErrorLocation(), "stages[1].axis_vector.s2");
}

TEST_F(ScenarioValidationTest, LinearMapNeedsANonZeroSlope) {
  scenario_.stages[0].map.rad_per_unit = 0.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.linear.rad_per_unit");
}

TEST_F(ScenarioValidationTest, LinearMapOffsetMustBeFinite) {
  scenario_.stages[0].map.offset_rad = kNaN;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.linear.offset_rad");
}

TEST_F(ScenarioValidationTest, PolynomialNeedsTwoToSixteenCoefficients) {
  scenario_.stages[1].map = Polynomial({0.5});
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  scenario_.stages[1].map = Polynomial(std::vector<double>(17, 1.0));
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  scenario_.stages[1].map = Polynomial(std::vector<double>(16, 1.0));
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, PolynomialMustNotBeConstant) {
  scenario_.stages[1].map = Polynomial({0.5, 0.0, 0.0});
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  EXPECT_THAT(ErrorMessage(), HasSubstr("constant"));
}

TEST_F(ScenarioValidationTest, NonMonotonicLookupTableNamesTheFirstOffendingIndex) {
  scenario_.stages[0].map = Table({0, 1, 2, 3, 4}, {0, 1, 3, 2, 1});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[3]");
  EXPECT_EQ(ErrorMessage(),
            "2 after 3 (the table increases before); a lookup table must be strictly monotonic");
}

TEST_F(ScenarioValidationTest, DecreasingLookupTableIsAccepted) {
  scenario_.stages[0].map = Table({0, 1, 2}, {3, 1, -2});
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, FlatLookupTableStartIsRejected) {
  scenario_.stages[0].map = Table({0, 1, 2}, {1, 1, 2});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[1]");
}

TEST_F(ScenarioValidationTest, LookupTableControlMustIncrease) {
  scenario_.stages[0].map = Table({0, 1, 1, 2}, {0, 1, 2, 3});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.control[2]");
}

TEST_F(ScenarioValidationTest, LookupTableColumnsMustPairUp) {
  scenario_.stages[0].map = Table({0, 1, 2}, {0, 1});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table");
}

TEST_F(ScenarioValidationTest, LookupTableNeedsTwoPoints) {
  scenario_.stages[0].map = Table({0}, {0});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.control");
}

TEST_F(ScenarioValidationTest, LookupTableValuesMustBeFinite) {
  scenario_.stages[0].map = Table({0, 1, 2}, {0, 1, kNaN});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[2]");
}

TEST_F(ScenarioValidationTest, EmptyRangeIsRejected) {
  scenario_.stages[1].range = ControlRange{1.0, 1.0};
  EXPECT_EQ(ErrorLocation(), "stages[1].range");
}

TEST_F(ScenarioValidationTest, NonFiniteRangeLimitIsNamed) {
  scenario_.stages[1].range = ControlRange{-kInf, 1.0};
  EXPECT_EQ(ErrorLocation(), "stages[1].range.min");
}

TEST_F(ScenarioValidationTest, AdjustableAxisStageNeedsAControl) {
  scenario_.stages[1] = QuarterWavePlate();
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.stages[1].orientation.controlled = false;
  EXPECT_EQ(ErrorLocation(), "stages[1].adjustable_axis");
}

TEST_F(ScenarioValidationTest, AdjustableAxisFixedAngleMustBeFinite) {
  scenario_.stages[1] = QuarterWavePlate();
  scenario_.stages[1].retardance.fixed_rad = kNaN;
  EXPECT_EQ(ErrorLocation(), "stages[1].adjustable_axis.retardance.fixed_rad");
}

TEST_F(ScenarioValidationTest, NaNInANestedMapIsNamedByItsFullPath) {
  scenario_.stages[0] = QuarterWavePlate();
  scenario_.stages[0].orientation.map = Polynomial({0.0, 2.0, 0.5});
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.stages[0].orientation.map.coefficients_rad[1] = kNaN;
  EXPECT_EQ(ErrorLocation(),
            "stages[0].adjustable_axis.orientation.controlled.map.polynomial.coefficients_rad[1]");
}

TEST_F(ScenarioValidationTest, AdjustableAxisRangeIsChecked) {
  scenario_.stages[0] = QuarterWavePlate();
  scenario_.stages[0].orientation.range = ControlRange{2.0, -2.0};
  EXPECT_EQ(ErrorLocation(), "stages[0].adjustable_axis.orientation.controlled.range");
}

TEST_F(ScenarioValidationTest, FieldsOfOtherKindsAreIgnored) {
  scenario_.stages[0].retardance.fixed_rad = kNaN;   // a fixed-axis stage
  scenario_.stages[1].map.coefficients_rad = {kNaN};  // a linear map
  scenario_.target.normal = Vector3::Zero();          // a point target
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

// ---- Input.

TEST_F(ScenarioValidationTest, NonUnitInitialSopIsRejected) {
  scenario_.input.initial_sop = StokesVector(0.0, 0.3, 0.4);
  EXPECT_EQ(ErrorLocation(), "input.initial_sop");
  EXPECT_THAT(ErrorMessage(), HasSubstr("|S| = 0.5"));
}

TEST_F(ScenarioValidationTest, NearlyUnitInitialSopIsAccepted) {
  scenario_.input.initial_sop = StokesVector(1.0 + 0.5e-6, 0.0, 0.0);
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, NonFiniteInitialSopComponentIsNamed) {
  scenario_.input.initial_sop = StokesVector(1.0, kNaN, 0.0);
  EXPECT_EQ(ErrorLocation(), "input.initial_sop.s2");
}

TEST_F(ScenarioValidationTest, AtMostSixteenDisturbances) {
  scenario_.input.disturbances.assign(17, DisturbanceConfig{});
  EXPECT_EQ(ErrorLocation(), "input.disturbances");
}

TEST_F(ScenarioValidationTest, NegativeRateIsRejected) {
  Scrambler().rate_rad_per_s = -1e5;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[0].paper_scrambler.rate_rad_per_s");
  EXPECT_THAT(ErrorMessage(), HasSubstr("use the axis direction to reverse"));
}

TEST_F(ScenarioValidationTest, RateOfPiPerSampleOrMoreIsRejected) {
  Scrambler().rate_rad_per_s = 3.2 * scenario_.simulation.sample_rate_hz;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[0].paper_scrambler.rate_rad_per_s");
  EXPECT_THAT(ErrorMessage(), HasSubstr("exceeds π"));
  EXPECT_THAT(ErrorMessage(), HasSubstr("simulation.sample_rate_hz"));
  Scrambler().rate_rad_per_s = 3.0 * scenario_.simulation.sample_rate_hz;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, ScramblerKickRatioMustBeNonNegative) {
  Scrambler().kick_rms_ratio = -0.5;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[0].paper_scrambler.kick_rms_ratio");
}

TEST_F(ScenarioValidationTest, ScramblerAxesMustBeNonZero) {
  Scrambler().axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "input.disturbances[0].paper_scrambler.rotation_axis_vector");
  Scrambler().axis = Vector3::UnitZ();
  Scrambler().kick_axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "input.disturbances[0].paper_scrambler.kick_axis_vector");
}

TEST_F(ScenarioValidationTest, RandomWalkDiffusionMustBeNonNegative) {
  DisturbanceConfig walk;
  walk.kind = DisturbanceConfig::Kind::kRandomWalk;
  walk.diffusion_rad_per_sqrt_s = -1.0;
  scenario_.input.disturbances.push_back(walk);
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].random_walk.diffusion_rad_per_sqrt_s");
}

TEST_F(ScenarioValidationTest, ConstantRotationIsChecked) {
  DisturbanceConfig rotation;
  rotation.kind = DisturbanceConfig::Kind::kConstantRotation;
  scenario_.input.disturbances.push_back(rotation);
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.input.disturbances[1].rate_rad_per_s = -1.0;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].constant_rotation.rate_rad_per_s");
  scenario_.input.disturbances[1].rate_rad_per_s = 1.0;
  scenario_.input.disturbances[1].axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].constant_rotation.axis_vector");
}

class ScenarioValidationBurstTest : public ScenarioValidationTest {
 protected:
  void SetUp() override {
    DisturbanceConfig burst;
    burst.kind = DisturbanceConfig::Kind::kTransientBurst;
    burst.start_s = 3e-3;
    burst.duration_s = 50e-6;
    burst.rate_rad_per_s = 5e6;
    burst.period_s = 1e-3;
    scenario_.input.disturbances.push_back(burst);
  }
  DisturbanceConfig& Burst() { return scenario_.input.disturbances[1]; }
};

TEST_F(ScenarioValidationBurstTest, ValidBurstIsAccepted) {
  EXPECT_EQ(ErrorLocation(), "(valid)");
  Burst().period_s = 0.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  Burst().period_s = Burst().duration_s;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationBurstTest, StartMustBeNonNegative) {
  Burst().start_s = -1e-3;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.start_s");
}

TEST_F(ScenarioValidationBurstTest, DurationMustBePositive) {
  Burst().duration_s = 0.0;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.duration_s");
}

TEST_F(ScenarioValidationBurstTest, PeakRateMustBeResolvable) {
  Burst().rate_rad_per_s = 1e9;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.rate_rad_per_s");
}

TEST_F(ScenarioValidationBurstTest, PeriodIsZeroOrAtLeastTheDuration) {
  Burst().period_s = 10e-6;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.period_s");
  Burst().period_s = -1e-3;
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.period_s");
}

TEST_F(ScenarioValidationBurstTest, AxisIsIgnoredWhenRandom) {
  Burst().axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "input.disturbances[1].transient_burst.axis_vector");
  Burst().random_axis = true;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

// ---- Target.

TEST_F(ScenarioValidationTest, NonUnitTargetPointIsRejected) {
  scenario_.target.point = StokesVector(0.0, 0.6, 0.9);
  EXPECT_EQ(ErrorLocation(), "target.point");
  EXPECT_THAT(ErrorMessage(), HasSubstr("|S| ="));
}

TEST_F(ScenarioValidationTest, TargetSetNeedsANonZeroNormal) {
  scenario_.target.kind = TargetConfig::Kind::kSet;
  scenario_.target.normal = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "target.set.normal");
}

TEST_F(ScenarioValidationTest, TargetSetMustBeACircle) {
  scenario_.target.kind = TargetConfig::Kind::kSet;
  scenario_.target.normal = Vector3(0.0, 0.0, 2.0);
  scenario_.target.offset = 1.9;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.target.offset = -2.0;
  EXPECT_EQ(ErrorLocation(), "target.set.offset");
}

// ---- Controller.

TEST_F(ScenarioValidationTest, NullspaceStepMustBeNonNegative) {
  scenario_.controller.nullspace_step = -0.1;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_step");
}

TEST_F(ScenarioValidationTest, ThresholdMustBeNonNegative) {
  scenario_.controller.threshold = -1.0;
  EXPECT_EQ(ErrorLocation(), "controller.threshold");
}

TEST_F(ScenarioValidationTest, DampingMustBeNonNegative) {
  scenario_.controller.damping = -1e-3;
  EXPECT_EQ(ErrorLocation(), "controller.damping");
}

TEST_F(ScenarioValidationTest, RegularizedLeastSquaresNeedsPositiveDamping) {
  scenario_.controller.damping = 0.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.method = ControlMethod::kRegularizedLeastSquares;
  EXPECT_EQ(ErrorLocation(), "controller.damping");
}

TEST_F(ScenarioValidationTest, SingularValueToleranceIsInTheOpenUnitInterval) {
  scenario_.controller.singular_value_tolerance = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.singular_value_tolerance");
  scenario_.controller.singular_value_tolerance = 1.0;
  EXPECT_EQ(ErrorLocation(), "controller.singular_value_tolerance");
}

TEST_F(ScenarioValidationTest, ActivationMustComeBeforeTheEnd) {
  scenario_.controller.activation_s = scenario_.simulation.duration_s;
  EXPECT_EQ(ErrorLocation(), "controller.activation_s");
  scenario_.controller.activation_s = -1e-3;
  EXPECT_EQ(ErrorLocation(), "controller.activation_s");
}

TEST_F(ScenarioValidationTest, InitialPhiHasOneValuePerControl) {
  scenario_.controller.initial_phi = {0.1, 0.2};
  EXPECT_EQ(ErrorLocation(), "controller.initial_phi");
  EXPECT_THAT(ErrorMessage(), HasSubstr("2 value(s) for 3 control(s)"));
  scenario_.controller.initial_phi = {0.1, kNaN, 0.3};
  EXPECT_EQ(ErrorLocation(), "controller.initial_phi[1]");
  scenario_.controller.initial_phi = {0.1, 0.2, 0.3};
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, InverseNeedsASquareTask) {
  scenario_.controller.method = ControlMethod::kInverse;
  EXPECT_EQ(ErrorLocation(), "(valid)");  // 3 controls, point target
  scenario_.stages = StagesFromAxes("3131");
  EXPECT_EQ(ErrorLocation(), "controller.method");
  EXPECT_THAT(ErrorMessage(), HasSubstr("INVERSE"));
}

TEST_F(ScenarioValidationTest, DampedWithASetTargetNeedsOneControl) {
  scenario_.controller.method = ControlMethod::kDamped;
  scenario_.target.kind = TargetConfig::Kind::kSet;
  EXPECT_EQ(ErrorLocation(), "controller.method");
  scenario_.stages = StagesFromAxes("1");
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, SingularityDampingIsChecked) {
  scenario_.controller.singularity_damping = SingularityDampingConfig{};
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.singularity_damping->max_damping = kNaN;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping.max_damping");
  scenario_.controller.singularity_damping->max_damping = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping.max_damping");
  scenario_.controller.singularity_damping->max_damping = 1e4;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping.max_damping");
  scenario_.controller.singularity_damping->max_damping = 0.5;
  scenario_.controller.singularity_damping->threshold = -1.0;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping.threshold");
  scenario_.controller.singularity_damping->threshold = kInf;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping.threshold");
  scenario_.controller.singularity_damping->threshold = 0.5;
  scenario_.controller.method = ControlMethod::kPseudoInverse;
  EXPECT_EQ(ErrorLocation(), "controller.singularity_damping");
  EXPECT_THAT(ErrorMessage(), HasSubstr("GP and GPT"));
}

TEST_F(ScenarioValidationTest, RangeCriterionNeedsGradientProjectionAndRanges) {
  scenario_.controller.nullspace_criterion = NullspaceCriterion::kRange;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_criterion");
  EXPECT_THAT(ErrorMessage(), HasSubstr("no stage has a range"));
  for (StageConfig& stage : scenario_.stages) stage.range = ControlRange{-1.0, 1.0};
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.method = ControlMethod::kExtendedJacobian;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_criterion");
}

TEST_F(ScenarioValidationTest, PredictionIsChecked) {
  scenario_.controller.prediction = PredictionConfig{};
  EXPECT_EQ(ErrorLocation(), "(valid)");
  PredictionConfig& q = *scenario_.controller.prediction;
  q.window_samples = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.window_samples");
  q.window_samples = kNaN;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.window_samples");
  q.window_samples = 1e10;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.window_samples");
  q.window_samples = 1000;
  q.horizon_samples = -1.0;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.horizon_samples");
  q.horizon_samples = kInf;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.horizon_samples");
  q.horizon_samples = 50.0;
  q.lead_samples = kNaN;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.lead_samples");
  q.lead_samples = -2.0;
  EXPECT_EQ(ErrorLocation(), "controller.prediction.lead_samples");
  q.lead_samples = 9.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.loop = LoopMode::kMeasured;
  EXPECT_EQ(ErrorLocation(), "controller.prediction");
  EXPECT_THAT(ErrorMessage(), HasSubstr("MODEL"));
  scenario_.controller.loop = LoopMode::kModel;
  scenario_.controller.method = ControlMethod::kDither;
  EXPECT_EQ(ErrorLocation(), "controller.prediction");
}

TEST_F(ScenarioValidationTest, DitherSettingsAreChecked) {
  scenario_.controller.dither.amplitude = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.dither.amplitude");
  scenario_.controller.dither.amplitude = 0.02;
  scenario_.controller.dither.settle_samples = -1;
  EXPECT_EQ(ErrorLocation(), "controller.dither.settle_samples");
  scenario_.controller.dither.settle_samples = 0;
  scenario_.controller.dither.reset_threshold = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.dither.reset_threshold");
  scenario_.controller.dither.reset_threshold = 1.0;
  scenario_.controller.dither.reset_duration_s = 0.5 / scenario_.simulation.sample_rate_hz;
  EXPECT_EQ(ErrorLocation(), "controller.dither.reset_duration_s");
  scenario_.controller.dither.reset_duration_s = 1.0 / scenario_.simulation.sample_rate_hz;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

// ---- Simulation.

TEST_F(ScenarioValidationTest, SampleRateMustBePositiveAndBounded) {
  scenario_.simulation.sample_rate_hz = 0.0;
  EXPECT_EQ(ErrorLocation(), "simulation.sample_rate_hz");
  scenario_.simulation.sample_rate_hz = 2e10;
  EXPECT_EQ(ErrorLocation(), "simulation.sample_rate_hz");
}

TEST_F(ScenarioValidationTest, DelayOfZeroIsRejected) {
  scenario_.simulation.delay_s = 0.0;
  EXPECT_EQ(ErrorLocation(), "simulation.delay_s");
  EXPECT_THAT(ErrorMessage(), HasSubstr("a command cannot act on the sample it was computed from"));
}

TEST_F(ScenarioValidationTest, DelayMustBeAWholeNumberOfSamples) {
  scenario_.simulation.delay_s = 30e-9;  // 1.5 samples at 50 MHz
  EXPECT_EQ(ErrorLocation(), "simulation.delay_s");
  EXPECT_THAT(ErrorMessage(), HasSubstr("1.5 samples is not a whole number"));
  scenario_.simulation.delay_s = 40e-9 * (1.0 + 1e-9);  // 2 samples, within the tolerance
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, DelayIsAtMostTenMillionSamples) {
  scenario_.simulation.delay_s = 1.0;  // 5e7 samples
  scenario_.simulation.duration_s = 2.0;
  EXPECT_EQ(ErrorLocation(), "simulation.delay_s");
}

TEST_F(ScenarioValidationTest, DurationMustBePositive) {
  scenario_.simulation.duration_s = 0.0;
  EXPECT_EQ(ErrorLocation(), "simulation.duration_s");
  scenario_.simulation.duration_s = 1e-9;  // 0.05 samples
  EXPECT_EQ(ErrorLocation(), "simulation.duration_s");
}

TEST_F(ScenarioValidationTest, OversizedRunIsRejected) {
  scenario_.simulation.duration_s = 1e5;  // 5e12 samples
  EXPECT_EQ(ErrorLocation(), "simulation.duration_s");
  EXPECT_THAT(ErrorMessage(), HasSubstr("oversized run"));
}

TEST_F(ScenarioValidationTest, PolarimeterNoiseIsAtMostHalfATurn) {
  scenario_.simulation.polarimeter_noise_deg = -1.0;
  EXPECT_EQ(ErrorLocation(), "simulation.polarimeter_noise_deg");
  scenario_.simulation.polarimeter_noise_deg = 181.0;
  EXPECT_EQ(ErrorLocation(), "simulation.polarimeter_noise_deg");
  scenario_.simulation.polarimeter_noise_deg = 180.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ScenarioValidationTest, LockThresholdIsInTheHalfOpenInterval) {
  scenario_.simulation.lock_threshold_deg = 0.0;
  EXPECT_EQ(ErrorLocation(), "simulation.lock_threshold_deg");
  scenario_.simulation.lock_threshold_deg = 180.5;
  EXPECT_EQ(ErrorLocation(), "simulation.lock_threshold_deg");
}

TEST_F(ScenarioValidationTest, StatisticsStartIsWithinTheRun) {
  scenario_.simulation.settle_samples = -1;
  EXPECT_EQ(ErrorLocation(), "simulation.settle_samples");
  scenario_.simulation.settle_samples = TotalSamples(scenario_.simulation) + 1;
  EXPECT_EQ(ErrorLocation(), "simulation.settle_samples");
  scenario_.simulation.settle_samples = 1000;
  scenario_.simulation.statistics_start_s = -1e-3;
  EXPECT_EQ(ErrorLocation(), "simulation.statistics_start_s");
  scenario_.simulation.statistics_start_s = scenario_.simulation.duration_s;
  EXPECT_EQ(ErrorLocation(), "simulation.statistics_start_s");
  scenario_.simulation.statistics_start_s = 5e-3;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

// ---- Helpers.

TEST_F(ScenarioValidationTest, ControlCountCountsControlledAngles) {
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 3);
  scenario_.stages.push_back(QuarterWavePlate());
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 4);
  scenario_.stages.back().retardance.controlled = true;
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 5);
  EXPECT_EQ(ScenarioControlCount({}), 0);
}

TEST_F(ScenarioValidationTest, SampleCountsAreRounded) {
  EXPECT_EQ(DelaySamples(scenario_.simulation), 50);
  EXPECT_EQ(TotalSamples(scenario_.simulation), 500000);
  SimulationConfig simulation;
  simulation.sample_rate_hz = 1e8;
  simulation.delay_s = 3e-8;  // 2.9999999999999996 samples in floating point
  EXPECT_EQ(DelaySamples(simulation), 3);
}

TEST_F(ScenarioValidationTest, SampleCountsSaturate) {
  SimulationConfig simulation;
  simulation.delay_s = kNaN;
  simulation.duration_s = 1e300;
  EXPECT_EQ(DelaySamples(simulation), 0);
  EXPECT_EQ(TotalSamples(simulation), std::numeric_limits<int64_t>::max());
}

}  // namespace
}  // namespace dpc
