#include "dpc/control/gradient_projection_law.h"

#include "dpc/control/jacobian_laws.h"

#include <gtest/gtest.h>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;
using testing::SvdPseudoInverse;

const Target kPaperTarget = Target::Point(StokesVector(0, 0.6, 0.8));

class GradientProjectionLawTest : public ::testing::Test, public ControlFixture {
 protected:
  GradientProjectionLawTest() : ControlFixture("3131") {}
};

TEST_F(GradientProjectionLawTest, MatchesThePapersEquationWithSvd) {
  // Paper eq. 12: Δφ = μ J⁺ΔS − μ_N (I − J⁺J) φ.
  GradientProjectionLaw law(0.1, 0.05);
  for (int trial = 0; trial < 30; ++trial) {
    const ControlVector phi = RandomPhi(1.5);
    ControlProblem& p = Build(phi, RandomSop(), kPaperTarget);
    ControlVector delta;
    ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
    const Eigen::MatrixXd j = FullTaskJacobian();
    const Eigen::MatrixXd pinv = SvdPseudoInverse(j);
    const Eigen::VectorXd phi_d = Eigen::VectorXd(phi);
    const Eigen::VectorXd expected =
        0.1 * pinv * FullTaskError() -
        0.05 * (Eigen::MatrixXd::Identity(4, 4) - pinv * j) * phi_d;
    EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-10 * std::max(1.0, expected.norm()));
    EXPECT_TRUE(law.diagnostics().nullspace_active);
  }
}

TEST_F(GradientProjectionLawTest, NullSpaceTermDoesNotMoveTheOutput) {
  // With the target reached, the update is the null-space term alone: J Δφ = 0.
  GradientProjectionLaw law(0.1, 0.5);
  const ControlVector phi = RandomPhi(1.5);
  const StokesVector s_in = RandomSop();
  const Target here = Target::Point(chain().Output(phi, s_in));
  ControlProblem& p = Build(phi, s_in, here);
  ControlVector delta;
  ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
  EXPECT_GT(delta.norm(), 1e-3);
  EXPECT_LT((p.kinematics.jacobian * delta).norm(), 1e-12);
}

TEST_F(GradientProjectionLawTest, ThresholdGatesTheNullSpaceTerm) {
  GradientProjectionLaw law(0.1, 0.5, 1.0);
  EXPECT_EQ(law.name(), "gpt");
  const StokesVector s_in = RandomSop();
  ControlVector small(4), large(4);
  small << 0.2, -0.5, 0.9, 0.1;
  large << 0.2, -1.2, 0.9, 0.1;
  ControlVector delta;
  law.ComputeUpdate(Build(small, s_in, kPaperTarget), &delta);
  EXPECT_FALSE(law.diagnostics().nullspace_active);
  PseudoInverseLaw pinv(0.1);
  ControlVector pinv_delta;
  pinv.ComputeUpdate(problem(), &pinv_delta);
  EXPECT_LT((delta - pinv_delta).norm(), 1e-15);
  law.ComputeUpdate(Build(large, s_in, kPaperTarget), &delta);
  EXPECT_TRUE(law.diagnostics().nullspace_active);
}

TEST_F(GradientProjectionLawTest, StaticLoopLocksAndMinimizesTheControlNorm) {
  // Without delay or motion, iterating φ ← φ + Δφ must reach S* and then keep reducing ‖φ‖
  // inside the fibre of controls that give S*.
  GradientProjectionLaw law(0.5, 0.2);
  const StokesVector s_in = StokesVector(0.3, -0.8, 0.52).normalized();
  ControlVector phi(4);
  phi << 1.7, -1.4, 1.1, 0.9;
  double locked_norm = -1.0;
  for (int k = 0; k < 400; ++k) {
    ControlProblem& p = Build(phi, s_in, kPaperTarget);
    ControlVector delta;
    ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
    phi += delta;
    if (k == 100) locked_norm = phi.norm();
  }
  const StokesVector s_out = chain().Output(phi, s_in);
  EXPECT_LT(kPaperTarget.DistanceRad(s_out), 1e-9);
  EXPECT_LT(phi.norm(), locked_norm);
  // Stationary: no null-space component left.
  ControlProblem& p = Build(phi, s_in, kPaperTarget);
  TaskPseudoInverse pinv;
  pinv.Compute(p.task_jacobian);
  ControlVector residual;
  pinv.NullSpaceProjection(phi, &residual);
  EXPECT_LT(residual.norm(), 1e-6);
}

TEST_F(GradientProjectionLawTest, RejectsBadParameters) {
  EXPECT_THROW(GradientProjectionLaw(0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, -0.1), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, 0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, NAN), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
