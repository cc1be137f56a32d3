#include "dpc/control/polarization_controller.h"

#include <gtest/gtest.h>

#include <cmath>

#include "dpc/control/control_integrator.h"
#include "dpc/control/jacobian_laws.h"
#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

const Target kPaperTarget = Target::Point(StokesVector(0.0, 0.6, 0.8));

/// Counts activations; Δφ = a fixed vector, or a failure.
class ScriptedLaw final : public ControlLaw {
 public:
  ScriptedLaw(int* activations, ControlStatus status) : activations_(activations), status_(status) {}
  void Activate(const ControlVector&) override { ++*activations_; }
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta) override {
    *delta = ControlVector::Constant(problem.control_count(), IsUsable(status_) ? 0.01 : 0.0);
    return status_;
  }
  std::string_view name() const override { return "scripted"; }

 private:
  int* activations_;
  ControlStatus status_;
};

ControlLawFactory Scripted(int* activations, ControlStatus status = ControlStatus::kOk) {
  return [=](const ControllerConfig&, const LawTiming&, int, bool) {
    return std::make_unique<ScriptedLaw>(activations, status);
  };
}

TEST(PolarizationControllerTest, AnUpdateIsTheProblemTheLawAndTheIntegratorOfThePaper) {
  // The same three steps written out by hand (eqs. 3, 5, 6) give the same bits on the general
  // path (a law factory keeps the controller off the fused one).
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  ControllerConfig config;
  config.step = 0.3;
  const ControlVector phi0 = (ControlVector(4) << 0.1, -0.2, 0.3, 0.05).finished();
  PolarizationController controller(chain, kPaperTarget, config, LawTiming{}, phi0, MakeControlLaw);
  ASSERT_FALSE(controller.fused());

  std::unique_ptr<ControlLaw> law = MakeControlLaw(config, LawTiming{}, 4, true);
  ControlIntegrator integrator(chain, phi0);
  law->Activate(integrator.phi());
  ControlProblem problem;
  problem.chain = &chain;
  problem.target = &kPaperTarget;
  problem.need_jacobian = law->needs_jacobian();
  ChainPose pose;
  ControlVector delta;
  StokesVector s_in = StokesVector(0.2, -0.7, 0.4).normalized();
  for (int k = 0; k < 50; ++k) {
    s_in = RotationAboutAxis(Vector3::UnitZ(), 0.05) * s_in;
    chain.ComputePose(integrator.phi(), &pose);
    problem.pose = &pose;
    problem.s_in = s_in;
    problem.s_out_measured = chain.Output(pose, s_in);
    UpdateControlProblem(&problem);
    integrator.Apply(law->ComputeUpdate(problem, &delta), delta);

    ControlInput input;
    input.s_in = s_in;
    input.s_out = problem.s_out_measured;
    controller.Update(input);
    ASSERT_EQ(controller.phi(), integrator.phi()) << "sample " << k;
  }
  EXPECT_LT(kPaperTarget.DistanceRad(chain.Output(controller.phi(), s_in)), 0.2);
}

// The fused update (fused_gradient_projection.h) against the general path on the same inputs:
// the paper's devices (axes at compile time) and another axis sequence (at run time), each law
// of its class, both loop modes, from a singular start (φ = 0 and S_in on the second stage's
// axis: T has rank 1, the near-singular fallback runs) and across a Reset.
struct FusedCase {
  const char* axes;
  ControlMethod method;
  LoopMode loop;
};

class FusedUpdateTest : public ::testing::TestWithParam<FusedCase> {};

TEST_P(FusedUpdateTest, FollowsTheGeneralPath) {
  const FusedCase c = GetParam();
  const WaveplateChain chain = WaveplateChain::FromAxes(c.axes);
  const int n = chain.control_count();
  ControllerConfig config;
  config.method = c.method;
  config.loop = c.loop;
  config.threshold = 0.2;  // gpt switches its null-space term on and off
  const ControlVector phi0 = ControlVector::Zero(n);
  PolarizationController fused(chain, kPaperTarget, config, LawTiming{}, phi0);
  PolarizationController general(chain, kPaperTarget, config, LawTiming{}, phi0, MakeControlLaw);
  ASSERT_TRUE(fused.fused());
  ASSERT_FALSE(general.fused());
  ControlInput input;
  input.s_in = chain.stages()[1].axis();
  const Matrix3 turn = RotationAboutAxis(Vector3(0.3, -0.2, 1.0).normalized(), 0.01);
  double worst = 0.0;
  int rank_deficient = 0;
  for (int k = 0; k < 3000; ++k) {
    if (k == 1500) {
      fused.Reset(phi0);
      general.Reset(phi0);
    }
    input.s_out = chain.Output(general.phi(), input.s_in);
    const ControlUpdate a = fused.Update(input);
    const ControlUpdate b = general.Update(input);
    input.s_in = turn * input.s_in;
    ASSERT_EQ(a.status, b.status) << k;
    ASSERT_EQ(a.outcome, b.outcome) << k;
    rank_deficient += a.status == ControlStatus::kRankDeficient;
    worst = std::max(worst, (fused.phi() - general.phi()).cwiseAbs().maxCoeff());
    ASSERT_EQ(fused.diagnostics().nullspace_active, general.diagnostics().nullspace_active) << k;
    ASSERT_EQ(fused.diagnostics().rank, general.diagnostics().rank) << k;
    ASSERT_NEAR(fused.diagnostics().singular_values.min(),
                general.diagnostics().singular_values.min(), 1e-9) << k;
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(rank_deficient, 0);
  // Tracking (not diverged): the lag of a rotation of 0.01 rad per update at step μ = 0.1 is
  // about 0.01·(1 − μ)/μ = 0.09 rad.
  EXPECT_LT(kPaperTarget.DistanceRad(chain.Output(fused.phi(), input.s_in)), 0.15);
}

INSTANTIATE_TEST_SUITE_P(
    Configurations, FusedUpdateTest,
    ::testing::Values(FusedCase{"131", ControlMethod::kGradientProjection, LoopMode::kModel},
                      FusedCase{"3131", ControlMethod::kGradientProjection, LoopMode::kModel},
                      FusedCase{"3131", ControlMethod::kThresholdedGradientProjection,
                                LoopMode::kMeasured},
                      FusedCase{"131", ControlMethod::kPseudoInverse, LoopMode::kMeasured},
                      FusedCase{"212", ControlMethod::kGradientProjection, LoopMode::kModel},
                      FusedCase{"2323", ControlMethod::kThresholdedGradientProjection,
                                LoopMode::kModel}));

TEST(PolarizationControllerTest, OnlyThePapersClassRunsFused) {
  const WaveplateChain paper = WaveplateChain::FromAxes("3131");
  EXPECT_TRUE(PolarizationController(paper, kPaperTarget, ControllerConfig{}, LawTiming{},
                                     ControlVector::Zero(4))
                  .fused());
  ControllerConfig rls;
  rls.method = ControlMethod::kRegularizedLeastSquares;
  EXPECT_FALSE(PolarizationController(paper, kPaperTarget, rls, LawTiming{}, ControlVector::Zero(4))
                   .fused());
  ControllerConfig predicting;
  predicting.prediction = PredictionConfig{};
  EXPECT_FALSE(PolarizationController(paper, kPaperTarget, predicting, LawTiming{},
                                      ControlVector::Zero(4))
                   .fused());
  const WaveplateChain five = WaveplateChain::FromAxes("31313");
  EXPECT_FALSE(PolarizationController(five, kPaperTarget, ControllerConfig{}, LawTiming{},
                                      ControlVector::Zero(5))
                   .fused());
  // A set target leaves the fused path, a point target brings it back.
  PolarizationController controller(paper, kPaperTarget, ControllerConfig{}, LawTiming{},
                                    ControlVector::Zero(4));
  const Target linear = Target::Set(Vector3::UnitZ(), 0.0);
  controller.SetTarget(linear);
  EXPECT_FALSE(controller.fused());
  controller.SetTarget(kPaperTarget);
  EXPECT_TRUE(controller.fused());
}

TEST(PolarizationControllerTest, ActivatesTheLawAtTheFirstUpdateAndAfterEveryReset) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  int activations = 0;
  PolarizationController controller(chain, kPaperTarget, ControllerConfig{}, LawTiming{},
                                    ControlVector::Zero(3), Scripted(&activations));
  EXPECT_EQ(activations, 0);
  controller.Update(ControlInput{});
  controller.Update(ControlInput{});
  EXPECT_EQ(activations, 1);
  EXPECT_NEAR(controller.phi()[0], 0.02, 1e-15);
  controller.Reset(ControlVector::Constant(3, 0.5));
  EXPECT_EQ(controller.phi(), ControlVector::Constant(3, 0.5));
  controller.Update(ControlInput{});
  EXPECT_EQ(activations, 2);
}

TEST(PolarizationControllerTest, AFailedUpdateIsNeverApplied) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  int activations = 0;
  PolarizationController controller(chain, kPaperTarget, ControllerConfig{}, LawTiming{},
                                    ControlVector::Constant(3, 0.25),
                                    Scripted(&activations, ControlStatus::kSingular));
  const ControlUpdate update = controller.Update(ControlInput{});
  EXPECT_EQ(update.status, ControlStatus::kSingular);
  EXPECT_EQ(update.outcome, ControlIntegrator::Outcome::kRejected);
  EXPECT_EQ(controller.phi(), ControlVector::Constant(3, 0.25));
}

TEST(PolarizationControllerTest, ANewTargetOfAnotherKindRebuildsTheLaw) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  int built = 0;
  ControlLawFactory counting = [&](const ControllerConfig& c, const LawTiming& t, int n, bool point) {
    ++built;
    return MakeControlLaw(c, t, n, point);
  };
  PolarizationController controller(chain, kPaperTarget, ControllerConfig{}, LawTiming{},
                                    ControlVector::Zero(3), counting);
  EXPECT_EQ(built, 1);
  const Target other_point = Target::Point(StokesVector::UnitZ());
  controller.SetTarget(other_point);
  EXPECT_EQ(built, 1);
  EXPECT_EQ(&controller.target(), &other_point);
  const Target linear = Target::Set(Vector3::UnitZ(), 0.0);
  controller.SetTarget(linear);
  EXPECT_EQ(built, 2);
  ControlInput input;
  input.s_in = StokesVector(0.3, 0.4, 0.866).normalized();
  for (int k = 0; k < 200; ++k) controller.Update(input);
  EXPECT_NEAR(chain.Output(controller.phi(), input.s_in).z(), 0.0, 1e-6);
  // A law that needs a square task does not fit a set target on 3 controls.
  ControllerConfig inverse;
  inverse.method = ControlMethod::kInverse;
  PolarizationController square(chain, kPaperTarget, inverse, LawTiming{}, ControlVector::Zero(3));
  EXPECT_THROW(square.SetTarget(linear), std::invalid_argument);
  EXPECT_EQ(&square.target(), &kPaperTarget);
}

TEST(PolarizationControllerTest, TheSampleClockPredictsAcrossTheLoopDelay) {
  // A deterministic rotation: aiming at the prediction tracks what the delayed loop would lag.
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  ControllerConfig config;
  config.step = 0.5;
  config.prediction = PredictionConfig{};
  PolarizationController controller(chain, kPaperTarget, config, LawTiming{1e4, 10}, ControlVector::Zero(3));
  ASSERT_NE(controller.compensator(), nullptr);
  const Matrix3 turn = RotationAboutAxis(Vector3::UnitZ(), 1e-3);
  ControlInput input;
  input.s_in = StokesVector(0.6, 0.0, 0.8);
  for (int k = 0; k < 3000; ++k) {
    input.s_in = turn * input.s_in;
    controller.Update(input);
  }
  // The command aims at the input 10 samples ahead.
  StokesVector ahead = input.s_in;
  for (int k = 0; k < 10; ++k) ahead = turn * ahead;
  EXPECT_LT(kPaperTarget.DistanceRad(chain.Output(controller.phi(), ahead)), 1e-3);
  EXPECT_GT(kPaperTarget.DistanceRad(chain.Output(controller.phi(), input.s_in)), 5e-3);
}

TEST(PolarizationControllerTest, ARateCommandKeepsTheOutputStillWhileTheInputTurns) {
  // Bench time at 10 kHz, the input turning at 200 rad/s about S3.
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  ControllerConfig config;
  config.step = 0.5;
  config.prediction = PredictionConfig{};
  PolarizationController controller(chain, kPaperTarget, config, LawTiming{1e4, 1}, ControlVector::Zero(4));
  const double omega_rad_per_s = 200.0;
  const Matrix3 turn = RotationAboutAxis(Vector3::UnitZ(), omega_rad_per_s * 1e-4);
  ControlInput input;
  input.s_in = StokesVector(0.6, 0.0, 0.8);
  input.rate_command = true;
  for (int k = 0; k < 2000; ++k) {
    input.s_in = turn * input.s_in;
    input.time_ns = int64_t{100'000} * k;
    input.horizon_s = 0.0;
    controller.Update(input);
  }
  // Differential kinematics where the update took the task (φ before its step, the measured
  // input): J φ̇ + (M ω) × S_out = 0 (ω about S3).
  ChainPose pose;
  chain.ComputePose(controller.problem().phi(), &pose);
  ChainKinematics k;
  chain.Evaluate(pose, input.s_in, &k);
  const Vector3 omega = omega_rad_per_s * Vector3::UnitZ();
  const Vector3 output_rate = k.jacobian * controller.rate_per_s() + (k.mueller * omega).cross(k.s_out);
  EXPECT_LT(output_rate.norm(), 1e-3 * omega_rad_per_s) << output_rate.transpose();
  EXPECT_GT(controller.rate_per_s().norm(), 10.0);
  // Following the ramp moves φ by the rate.
  const ControlVector before = controller.phi();
  controller.AdvanceAlongRate(1e-4);
  EXPECT_LT((controller.phi() - before - controller.rate_per_s() * 1e-4).norm(), 1e-12);
}

}  // namespace
}  // namespace dpc
