#include "dpc/control/fused_gradient_projection.h"

#include <gtest/gtest.h>

#include <type_traits>

#include "dpc/control/gradient_projection_law.h"
#include "dpc/control/jacobian_laws.h"
#include "dpc/control/polarization_controller.h"
#include "support/control_fixture.h"

namespace dpc {
namespace {

const Target kPaperTarget = Target::Point(StokesVector(0.0, 0.6, 0.8));

TEST(PlanFusedUpdateTest, ThePapersClassIsPlanned) {
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  ControllerConfig config;
  config.step = 0.2;
  config.nullspace_step = 0.05;
  const std::optional<FusedUpdatePlan> plan = PlanFusedUpdate(chain, kPaperTarget, config);
  ASSERT_TRUE(plan);
  EXPECT_EQ(plan->stages, 4);
  EXPECT_EQ(plan->axis[0], ElementalAxis::kS3);
  EXPECT_EQ(plan->axis[3], ElementalAxis::kS1);
  EXPECT_DOUBLE_EQ(plan->rad_per_unit[2], M_PI);
  EXPECT_EQ(plan->step, 0.2);
  EXPECT_EQ(plan->nullspace_step, 0.05);
  EXPECT_FALSE(plan->threshold);
  EXPECT_EQ(plan->target_point, kPaperTarget.point());

  ControllerConfig pinv;
  pinv.method = ControlMethod::kPseudoInverse;
  EXPECT_EQ(PlanFusedUpdate(chain, kPaperTarget, pinv)->nullspace_step, 0.0);
  ControllerConfig gpt;
  gpt.method = ControlMethod::kThresholdedGradientProjection;
  gpt.threshold = 0.4;
  EXPECT_EQ(PlanFusedUpdate(chain, kPaperTarget, gpt)->threshold, 0.4);
  // Other elemental axes and offsets are in the class too.
  std::vector<WaveplateStage> stages;
  for (const char axis : std::string("232")) {
    const Vector3 unit = ElementalAxisVector(static_cast<ElementalAxis>(axis - '0'));
    stages.push_back(WaveplateStage::FixedAxis(unit, ControlMap::Linear(2.0, 0.3)));
  }
  const std::optional<FusedUpdatePlan> other =
      PlanFusedUpdate(WaveplateChain(std::move(stages)), kPaperTarget, ControllerConfig{});
  ASSERT_TRUE(other);
  EXPECT_EQ(other->offset_rad[1], 0.3);
}

TEST(PlanFusedUpdateTest, EverythingElseRunsOnTheGeneralPath) {
  const WaveplateChain paper = WaveplateChain::FromAxes("131");
  const auto planned = [](const WaveplateChain& chain, const Target& target,
                          const ControllerConfig& config) {
    return PlanFusedUpdate(chain, target, config).has_value();
  };
  EXPECT_TRUE(planned(paper, kPaperTarget, ControllerConfig{}));
  EXPECT_FALSE(planned(WaveplateChain::FromAxes("13131"), kPaperTarget, ControllerConfig{}));
  EXPECT_FALSE(planned(WaveplateChain::FromAxes("13"), kPaperTarget, ControllerConfig{}));
  EXPECT_FALSE(planned(paper, Target::Set(Vector3::UnitZ(), 0.0), ControllerConfig{}));
  for (ControlMethod method : {ControlMethod::kTranspose, ControlMethod::kDamped,
                               ControlMethod::kRegularizedLeastSquares,
                               ControlMethod::kExtendedJacobian, ControlMethod::kDither}) {
    ControllerConfig config;
    config.method = method;
    EXPECT_FALSE(planned(paper, kPaperTarget, config));
  }
  ControllerConfig predicting, damped, correcting, ranging;
  predicting.prediction = PredictionConfig{};
  damped.singularity_damping = SingularityDampingConfig{};
  correcting.curvature_correction = true;
  ranging.nullspace_criterion = NullspaceCriterion::kRange;
  for (const ControllerConfig* config : {&predicting, &damped, &correcting, &ranging}) {
    EXPECT_FALSE(planned(paper, kPaperTarget, *config));
  }
  const auto chain_of = [](WaveplateStage middle) {
    std::vector<WaveplateStage> stages{WaveplateStage::FixedAxis(Vector3::UnitX()), middle,
                                       WaveplateStage::FixedAxis(Vector3::UnitX())};
    return WaveplateChain(std::move(stages));
  };
  EXPECT_FALSE(planned(chain_of(WaveplateStage::FixedAxis(Vector3(1, 1, 0))), kPaperTarget,
                       ControllerConfig{}));
  EXPECT_FALSE(planned(chain_of(WaveplateStage::FixedAxis(
                           Vector3::UnitZ(), ControlMap::Polynomial({0.0, 3.0, 0.1}))),
                       kPaperTarget, ControllerConfig{}));
  EXPECT_FALSE(planned(chain_of(WaveplateStage::FixedAxis(Vector3::UnitZ(), ControlMap::Linear(),
                                                          ControlRange{-1.0, 1.0})),
                       kPaperTarget, ControllerConfig{}));
  EXPECT_FALSE(planned(chain_of(WaveplateStage::AdjustableAxis(StageAngle::Fixed(M_PI / 2),
                                                               StageAngle::Controlled(
                                                                   ControlMap::Linear()))),
                       kPaperTarget, ControllerConfig{}));
}

// One update of the fused kernel against the general path's problem and law on the same pose
// and input, over random poses: Δφ, the new pose, the diagnostics.
template <typename Axes>
void ExpectOneUpdateEqualsTheGeneralPath(const std::string& text, ControlMethod method,
                                         LoopMode loop) {
  constexpr int N = Axes::kStages;
  testing::ControlFixture fixture(text);
  const WaveplateChain& chain = fixture.chain();
  ControllerConfig config;
  config.method = method;
  config.loop = loop;
  config.threshold = 0.5;
  const FusedUpdatePlan plan = *PlanFusedUpdate(chain, kPaperTarget, config);
  Axes axes;
  if constexpr (!Axes::kFixed) {
    for (int e = 0; e < N; ++e) axes.axis[e] = plan.axis[e];
  }
  FusedGradientProjection<Axes> fused(plan, axes);
  std::unique_ptr<ControlLaw> law = MakeControlLaw(config, LawTiming{}, N, true);
  for (int trial = 0; trial < 300; ++trial) {
    const ControlVector phi = fixture.RandomPhi();
    const StokesVector s_in = fixture.RandomSop();
    const StokesVector s_out = fixture.RandomSop();  // a measurement the model does not explain
    ControlProblem& problem = fixture.Build(phi, s_in, kPaperTarget, loop, s_out);
    ControlVector expected;
    const ControlStatus status = law->ComputeUpdate(problem, &expected);
    ElementalPose<N> pose;
    for (int e = 0; e < N; ++e) pose.phi[e] = phi[e];
    fused.ExactPose(&pose);
    double delta[N];
    const FusedUpdateResult result = fused.Update(s_in, s_out, &pose, delta);
    ASSERT_TRUE(result.applied);
    EXPECT_EQ(result.rank, law->diagnostics().rank);
    EXPECT_EQ(result.nullspace_active, law->diagnostics().nullspace_active);
    EXPECT_EQ(status == ControlStatus::kRankDeficient, result.rank < 2);
    EXPECT_NEAR(result.singular_values.min(), law->diagnostics().singular_values.min(), 1e-12);
    for (int e = 0; e < N; ++e) {
      // Random poses reach det G ≈ 1e-6·tr²G, a condition number of ~1e6: round-off ~1e-10.
      EXPECT_NEAR(delta[e], expected[e], 1e-10 * (1.0 + std::abs(expected[e]))) << text << e;
      EXPECT_EQ(pose.phi[e], phi[e] + delta[e]);
    }
    // The new pose is the exact one of the new φ (to the series' and angle addition's round-off).
    ChainPose exact;
    chain.ComputePose(phi + Eigen::Map<const ControlVector>(delta, N), &exact);
    for (int e = 0; e < N; ++e) {
      EXPECT_NEAR(pose.cos[e], exact.cos[e], 2e-15);
      EXPECT_NEAR(pose.sin[e], exact.sin[e], 2e-15);
    }
  }
}

TEST(FusedGradientProjectionTest, OneUpdateEqualsTheGeneralPath) {
  ExpectOneUpdateEqualsTheGeneralPath<PaperAxes3>("131", ControlMethod::kGradientProjection,
                                                  LoopMode::kModel);
  ExpectOneUpdateEqualsTheGeneralPath<PaperAxes4>("3131", ControlMethod::kGradientProjection,
                                                  LoopMode::kMeasured);
  ExpectOneUpdateEqualsTheGeneralPath<PaperAxes4>(
      "3131", ControlMethod::kThresholdedGradientProjection, LoopMode::kModel);
  ExpectOneUpdateEqualsTheGeneralPath<PaperAxes3>("131", ControlMethod::kPseudoInverse,
                                                  LoopMode::kMeasured);
  ExpectOneUpdateEqualsTheGeneralPath<RuntimeStageAxes<3>>(
      "232", ControlMethod::kGradientProjection, LoopMode::kModel);
  ExpectOneUpdateEqualsTheGeneralPath<RuntimeStageAxes<4>>(
      "1212", ControlMethod::kGradientProjection, LoopMode::kMeasured);
}

TEST(FusedGradientProjectionTest, ANonFiniteInputChangesNothing) {
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  FusedGradientProjection<PaperAxes4> fused(*PlanFusedUpdate(chain, kPaperTarget, ControllerConfig{}),
                                            PaperAxes4{});
  ElementalPose<4> pose;
  pose.phi = Lanes{0.1, 0.2, 0.3, 0.4};
  fused.ExactPose(&pose);
  const ElementalPose<4> before = pose;
  double delta[4] = {1, 1, 1, 1};
  const FusedUpdateResult result =
      fused.Update(StokesVector(NAN, 0.0, 1.0), StokesVector::UnitX(), &pose, delta);
  EXPECT_FALSE(result.applied);
  for (int e = 0; e < 4; ++e) {
    EXPECT_EQ(delta[e], 0.0);
    EXPECT_EQ(pose.phi[e], before.phi[e]);
    EXPECT_EQ(pose.cos[e], before.cos[e]);
  }
}

TEST(FusedControlStepTest, KeepsItsCommandAcrossUpdates) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  std::unique_ptr<FusedControlStep> step =
      FusedControlStep::Make(*PlanFusedUpdate(chain, kPaperTarget, ControllerConfig{}));
  ControlVector phi = ControlVector::Constant(3, 0.2), delta;
  step->SetCommand(phi);
  StokesVector s_in = StokesVector(0.3, 0.4, 0.866).normalized();
  for (int k = 0; k < 400; ++k) {
    ASSERT_TRUE(step->Update(s_in, s_in, &delta).applied);
    phi += delta;
  }
  EXPECT_LT(kPaperTarget.DistanceRad(chain.Output(phi, s_in)), 1e-6);
  // A pose handed in replaces the command.
  ChainPose pose;
  chain.ComputePose(ControlVector::Zero(3), &pose);
  step->SetPose(pose);
  step->Update(s_in, s_in, &delta);
  ControlVector expected;
  PolarizationController general(chain, kPaperTarget, ControllerConfig{}, LawTiming{},
                                 ControlVector::Zero(3), MakeControlLaw);
  ControlInput input;
  input.s_in = input.s_out = s_in;
  general.Update(input);
  EXPECT_LT((general.phi() - delta).cwiseAbs().maxCoeff(), 1e-14);
}

}  // namespace
}  // namespace dpc
