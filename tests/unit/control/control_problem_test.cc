#include "dpc/control/control_problem.h"

#include <gtest/gtest.h>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;
using testing::SvdPseudoInverse;

class ControlProblemTest : public ::testing::Test, public ControlFixture {
 protected:
  ControlProblemTest() : ControlFixture("3131") {}
};

TEST_F(ControlProblemTest, TangentReductionGivesTheSamePseudoInverseSolution) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  for (int trial = 0; trial < 50; ++trial) {
    ControlProblem& p = Build(RandomPhi(), RandomSop(), target);
    ASSERT_EQ(p.task_jacobian.rows(), 2);
    const Eigen::VectorXd full = SvdPseudoInverse(FullTaskJacobian()) * FullTaskError();
    const Eigen::VectorXd reduced =
        SvdPseudoInverse(Eigen::MatrixXd(p.task_jacobian)) * Eigen::VectorXd(p.task_error);
    EXPECT_LT((full - reduced).norm(), 1e-10 * std::max(1.0, full.norm()));
  }
}

TEST_F(ControlProblemTest, TangentReductionKeepsTransposeAndRegularizedSolutions) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  const double lambda = 0.05;
  for (int trial = 0; trial < 50; ++trial) {
    ControlProblem& p = Build(RandomPhi(), RandomSop(), target);
    const Eigen::MatrixXd j = FullTaskJacobian();
    const Eigen::MatrixXd t = p.task_jacobian;
    const Eigen::VectorXd e3 = FullTaskError(), e2 = p.task_error;
    EXPECT_LT((j.transpose() * e3 - t.transpose() * e2).norm(), 1e-13);
    const Eigen::VectorXd rls3 =
        j.transpose() * (j * j.transpose() + lambda * Eigen::Matrix3d::Identity()).inverse() * e3;
    const Eigen::VectorXd rls2 =
        t.transpose() * (t * t.transpose() + lambda * Eigen::Matrix2d::Identity()).inverse() * e2;
    EXPECT_LT((rls3 - rls2).norm(), 1e-12);
  }
}

TEST_F(ControlProblemTest, TaskJacobianIsTheInputFrameJacobianInTangentCoordinates) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  ControlProblem& p = Build(RandomPhi(), RandomSop(), target);
  Eigen::Matrix<double, 2, 3> e;
  e.row(0) = p.tangent_e1.transpose();
  e.row(1) = p.tangent_e2.transpose();
  // T = Eᵀ MᵀJ with E the tangent basis at S_in.
  EXPECT_LT(p.tangent_e1.dot(p.s_in), 1e-15);
  EXPECT_LT((Eigen::MatrixXd(p.task_jacobian) -
             e * p.kinematics.mueller.transpose() * p.kinematics.jacobian)
                .norm(),
            1e-13);
}

TEST_F(ControlProblemTest, SetTargetTaskIsNormalTimesJacobian) {
  const Target target = Target::Set(Vector3::UnitZ(), 0.2);
  ControlProblem& p = Build(RandomPhi(), RandomSop(), target);
  ASSERT_EQ(p.task_jacobian.rows(), 1);
  EXPECT_LT((Eigen::MatrixXd(p.task_jacobian) - FullTaskJacobian()).norm(), 1e-13);
  EXPECT_NEAR(p.task_error[0], 0.2 - p.kinematics.s_out.z(), 1e-15);
}

TEST_F(ControlProblemTest, LoopModeChoosesTheOutputInTheError) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  const ControlVector phi = RandomPhi();
  const StokesVector s_in = RandomSop();
  const StokesVector measured = RandomSop();
  ControlProblem& model = Build(phi, s_in, target, LoopMode::kModel, measured);
  EXPECT_EQ(model.s_out_for_error, model.kinematics.s_out);
  ControlProblem& meas = Build(phi, s_in, target, LoopMode::kMeasured, measured);
  EXPECT_EQ(meas.s_out_for_error, measured);
  EXPECT_LT((meas.PointError() - (target.point() - measured)).norm(), 1e-15);
}

}  // namespace
}  // namespace dpc
