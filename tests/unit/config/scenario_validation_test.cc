// Tests of the scenario as a whole (scenario_validation.cc): the error ValidateScenario
// reports, the simulation, input and target checks, and the sample counts. Each test breaks one
// field of the paper's scenario and checks where ValidateScenario locates the error.

#include "dpc/config/scenario_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "support/scenario_fixture.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using testing::kNaN;

class ScenarioValidationTest : public testing::ScenarioFixture {
 protected:
  DisturbanceConfig& Scrambler() { return scenario_.input.disturbances[0]; }
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

TEST_F(ScenarioValidationTest, ARecordedInputIsTheWholeInputOfUnitSops) {
  auto recorded = std::make_shared<RecordedInput>();
  recorded->source = "session.mcap";
  recorded->sops = {StokesVector::UnitX(), StokesVector::UnitZ()};
  scenario_.input.recorded = recorded;
  scenario_.input.initial_sop = StokesVector(0.0, 0.3, 0.4);  // not used beside a recording
  EXPECT_EQ(ErrorLocation(), "input.disturbances");  // the paper's scrambler beside it
  EXPECT_THAT(ErrorMessage(), HasSubstr("beside a recorded input (session.mcap)"));
  scenario_.input.disturbances.clear();
  EXPECT_EQ(ErrorLocation(), "(valid)");
  recorded->sops.push_back(StokesVector(0.0, kNaN, 1.0));
  EXPECT_EQ(ErrorLocation(), "input.recorded[2].s2");
  recorded->sops.back() = StokesVector(0.0, 0.6, 0.6);
  EXPECT_EQ(ErrorLocation(), "input.recorded[2]");
  recorded->sops.clear();
  EXPECT_EQ(ErrorLocation(), "input.recorded");
  EXPECT_THAT(ErrorMessage(), HasSubstr("session.mcap: no sample"));
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

// ---- Sample counts.

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
