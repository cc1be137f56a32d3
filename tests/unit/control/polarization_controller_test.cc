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
  // The same three steps written out by hand (eqs. 3, 5, 6) give the same bits.
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  ControllerConfig config;
  config.step = 0.3;
  const ControlVector phi0 = (ControlVector(4) << 0.1, -0.2, 0.3, 0.05).finished();
  PolarizationController controller(chain, kPaperTarget, config, LawTiming{}, phi0);

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
