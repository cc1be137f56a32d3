// Tests of the controller part of the scenario validation (controller_validation.cc): the
// control law's settings, the dither and the options beyond the paper. Each test breaks one
// field of the paper's scenario and checks where ValidateScenario locates the error.

#include "dpc/config/scenario_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "support/scenario_fixture.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using testing::kInf;
using testing::kNaN;

class ControllerValidationTest : public testing::ScenarioFixture {};

// ---- The control law's settings.

TEST_F(ControllerValidationTest, AnAbsurdStepIsRefusedForEveryLaw) {
  scenario_.controller.step = 1e308;
  EXPECT_EQ(ErrorLocation(), "controller.step");
  scenario_.controller.method = ControlMethod::kTranspose;
  EXPECT_EQ(ErrorLocation(), "controller.step");
}

TEST_F(ControllerValidationTest, AScaleFreeLawsStepIsBelowTwo) {
  // gp: the task error is multiplied by (1 − μ) per update; μ = 2 never converges.
  scenario_.controller.step = 2.0;
  EXPECT_EQ(ErrorLocation(), "controller.step");
  scenario_.controller.step = 1.99;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  // The transpose law's step scales with the device's Jacobian: larger steps are legitimate.
  scenario_.controller.method = ControlMethod::kTranspose;
  scenario_.controller.step = 50.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ControllerValidationTest, TheNullspaceStepIsBelowTwo) {
  scenario_.controller.nullspace_step = 2.0;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_step");
}

TEST_F(ControllerValidationTest, NullspaceStepMustBeNonNegative) {
  scenario_.controller.nullspace_step = -0.1;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_step");
}

TEST_F(ControllerValidationTest, ThresholdMustBeNonNegative) {
  scenario_.controller.threshold = -1.0;
  EXPECT_EQ(ErrorLocation(), "controller.threshold");
}

TEST_F(ControllerValidationTest, DampingMustBeNonNegative) {
  scenario_.controller.damping = -1e-3;
  EXPECT_EQ(ErrorLocation(), "controller.damping");
}

TEST_F(ControllerValidationTest, RegularizedLeastSquaresNeedsPositiveDamping) {
  scenario_.controller.damping = 0.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.method = ControlMethod::kRegularizedLeastSquares;
  EXPECT_EQ(ErrorLocation(), "controller.damping");
}

TEST_F(ControllerValidationTest, SingularValueToleranceIsInTheOpenUnitInterval) {
  scenario_.controller.singular_value_tolerance = 0.0;
  EXPECT_EQ(ErrorLocation(), "controller.singular_value_tolerance");
  scenario_.controller.singular_value_tolerance = 1.0;
  EXPECT_EQ(ErrorLocation(), "controller.singular_value_tolerance");
}

TEST_F(ControllerValidationTest, ActivationMustComeBeforeTheEnd) {
  scenario_.controller.activation_s = scenario_.simulation.duration_s;
  EXPECT_EQ(ErrorLocation(), "controller.activation_s");
  scenario_.controller.activation_s = -1e-3;
  EXPECT_EQ(ErrorLocation(), "controller.activation_s");
}

TEST_F(ControllerValidationTest, InitialPhiHasOneValuePerControl) {
  scenario_.controller.initial_phi = {0.1, 0.2};
  EXPECT_EQ(ErrorLocation(), "controller.initial_phi");
  EXPECT_THAT(ErrorMessage(), HasSubstr("2 value(s) for 3 control(s)"));
  scenario_.controller.initial_phi = {0.1, kNaN, 0.3};
  EXPECT_EQ(ErrorLocation(), "controller.initial_phi[1]");
  scenario_.controller.initial_phi = {0.1, 0.2, 0.3};
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ControllerValidationTest, InverseNeedsASquareTask) {
  scenario_.controller.method = ControlMethod::kInverse;
  EXPECT_EQ(ErrorLocation(), "(valid)");  // 3 controls, point target
  scenario_.stages = StagesFromAxes("3131");
  EXPECT_EQ(ErrorLocation(), "controller.method");
  EXPECT_THAT(ErrorMessage(), HasSubstr("INVERSE"));
}

TEST_F(ControllerValidationTest, DampedWithASetTargetNeedsOneControl) {
  scenario_.controller.method = ControlMethod::kDamped;
  scenario_.target.kind = TargetConfig::Kind::kSet;
  EXPECT_EQ(ErrorLocation(), "controller.method");
  scenario_.stages = StagesFromAxes("1");
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

// ---- Options beyond the paper.

TEST_F(ControllerValidationTest, SingularityDampingIsChecked) {
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

TEST_F(ControllerValidationTest, RangeCriterionNeedsGradientProjectionAndRanges) {
  scenario_.controller.nullspace_criterion = NullspaceCriterion::kRange;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_criterion");
  EXPECT_THAT(ErrorMessage(), HasSubstr("no stage has a range"));
  for (StageConfig& stage : scenario_.stages) stage.range = ControlRange{-1.0, 1.0};
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.controller.method = ControlMethod::kExtendedJacobian;
  EXPECT_EQ(ErrorLocation(), "controller.nullspace_criterion");
}

TEST_F(ControllerValidationTest, ThresholdedNullSpaceMustBeReachableInsideTheRanges) {
  // gpt's null-space term runs only while some |phi_i| exceeds the threshold; with every control
  // inside a range whose ends are within it, it never would.
  scenario_.controller.method = ControlMethod::kThresholdedGradientProjection;
  scenario_.controller.threshold = 1.0;
  EXPECT_EQ(ErrorLocation(), "(valid)");  // no ranges: phi may exceed anything
  for (StageConfig& stage : scenario_.stages) stage.range = ControlRange{-1.0, 1.0};
  EXPECT_EQ(ErrorLocation(), "controller.threshold");
  EXPECT_THAT(ErrorMessage(), HasSubstr("the term would never run; give a threshold below 1"));
  scenario_.controller.nullspace_criterion = NullspaceCriterion::kRange;
  EXPECT_EQ(ErrorLocation(), "controller.threshold");
  scenario_.controller.threshold = 0.8;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  // One control's range reaching beyond the threshold is enough ...
  scenario_.controller.threshold = 1.0;
  scenario_.stages[1].range = ControlRange{0.5, 1.5};
  EXPECT_EQ(ErrorLocation(), "(valid)");
  // ... and so is a control without a range.
  scenario_.stages[1].range = ControlRange{-1.0, 1.0};
  scenario_.stages[2].range.reset();
  scenario_.controller.nullspace_criterion = NullspaceCriterion::kMinimumNorm;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  // gp has no threshold.
  for (StageConfig& stage : scenario_.stages) stage.range = ControlRange{-1.0, 1.0};
  scenario_.controller.method = ControlMethod::kGradientProjection;
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(ControllerValidationTest, PredictionIsChecked) {
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

// ---- Dither.

TEST_F(ControllerValidationTest, DitherSettingsAreChecked) {
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

}  // namespace
}  // namespace dpc
