#include "dpc/control/delay_compensator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "dpc/optics/rotation.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {
namespace {

TEST(DelayCompensatorTest, IntegratorLagIsOneMinusStepOverStep) {
  EXPECT_DOUBLE_EQ(IntegratorLagSamples(0.1), 9.0);
  EXPECT_DOUBLE_EQ(IntegratorLagSamples(0.5), 1.0);
  EXPECT_DOUBLE_EQ(IntegratorLagSamples(1.0), 0.0);
  EXPECT_DOUBLE_EQ(IntegratorLagSamples(1.5), 0.0);
}

TEST(DelayCompensatorTest, LeadAddsTheMotionOfThePredictionToTheTaskError) {
  // e ← e + L·m with m = −Eᵀ(P_k − P_(k−1)): for a point target the tangent components of the
  // prediction's last step, scaled by −L.
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  DelayCompensator compensator(500, 9.0);
  const Matrix3 step = R3(1e-3);
  StokesVector s = StokesVector(0.6, 0.0, 0.8);
  StokesVector p_previous, p_current;
  for (int k = 0; k < 100; ++k, s = step * s) {
    p_previous = p_current;
    p_current = compensator.Predict(s, 50.0);
  }
  ChainPose pose;
  chain.ComputePose(ControlVector::Constant(3, 0.2), &pose);
  ControlProblem problem;
  problem.chain = &chain;
  problem.target = &target;
  problem.pose = &pose;
  problem.s_in = p_current;
  UpdateControlProblem(&problem);
  const TaskVector plain = problem.task_error;
  compensator.AddLead(&problem);
  const Vector3 motion = p_current - p_previous;
  EXPECT_NEAR(problem.task_error[0], plain[0] - 9.0 * problem.tangent_e1.dot(motion), 1e-15);
  EXPECT_NEAR(problem.task_error[1], plain[1] - 9.0 * problem.tangent_e2.dot(motion), 1e-15);
  EXPECT_NEAR(motion.norm(), 0.6e-3, 1e-6);  // 1e-3 rad on an orbit of radius 0.6
}

TEST(DelayCompensatorTest, TimeBasedPredictionCrossesTheLatency) {
  const double rate = 300.0, period = 1e-4;
  DelayCompensator compensator(100, 0.0, period);
  const StokesVector start = StokesVector(0.6, 0.0, 0.8);
  StokesVector prediction;
  double t = 0.0;
  for (int k = 0; k < 300; ++k) {
    t = k * period;
    prediction = compensator.PredictAt(R3(rate * t) * start, t, 2.5e-4);
  }
  EXPECT_LT((prediction - R3(rate * (t + 2.5e-4)) * start).norm(), 1e-9);
}

TEST(DelayCompensatorTest, WithoutHorizonItIsTheMeasurement) {
  DelayCompensator compensator(100, 0.0);
  const StokesVector s = StokesVector(0.0, 0.6, 0.8);
  EXPECT_LT((compensator.Predict(s, 0.0) - s).norm(), 1e-15);
}

TEST(DelayCompensatorTest, RejectsABadLead) {
  EXPECT_THROW(DelayCompensator(100, -1.0), std::invalid_argument);
  EXPECT_THROW(DelayCompensator(100, std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  EXPECT_THROW(DelayCompensator(0.0, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
