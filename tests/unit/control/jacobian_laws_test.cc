#include "dpc/control/jacobian_laws.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;
using testing::SvdPseudoInverse;

const Target kPaperTarget = Target::Point(StokesVector(0, 0.6, 0.8));

class JacobianLawsTest : public ::testing::Test {
 protected:
  ControlFixture three_{"131"};
  ControlFixture four_{"3131"};
};

TEST_F(JacobianLawsTest, InverseReportsTheSingularityOfEveryThreeStageJacobian) {
  InverseJacobianLaw law(0.5);
  for (int trial = 0; trial < 100; ++trial) {
    ControlProblem& p = three_.Build(three_.RandomPhi(), three_.RandomSop(), kPaperTarget);
    ControlVector delta;
    EXPECT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kSingular);
    EXPECT_EQ(delta.size(), 3);
    EXPECT_EQ(delta.norm(), 0.0);
    EXPECT_LE(law.diagnostics().rank, 2);
  }
}

TEST_F(JacobianLawsTest, InverseSolvesASquareOneDimensionalTask) {
  ControlFixture one("1");
  InverseJacobianLaw law(1.0);
  const Target set = Target::Set(Vector3::UnitZ(), 0.1);
  ControlProblem& p = one.Build(one.RandomPhi(), StokesVector(0, 0.6, 0.8), set);
  ControlVector delta;
  ASSERT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kOk);
  EXPECT_NEAR(delta[0], p.task_error[0] / p.task_jacobian(0, 0), 1e-15);
}

TEST_F(JacobianLawsTest, TransposeIsStepTimesJacobianTransposeError) {
  TransposeJacobianLaw law(0.3);
  for (int trial = 0; trial < 20; ++trial) {
    ControlProblem& p = four_.Build(four_.RandomPhi(), four_.RandomSop(), kPaperTarget);
    ControlVector delta;
    ASSERT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kOk);
    const Eigen::VectorXd expected =
        0.3 * four_.FullTaskJacobian().transpose() * four_.FullTaskError();
    EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-13);
  }
}

TEST_F(JacobianLawsTest, DampedIsThePapersJPlusLambdaIInverse) {
  DampedJacobianLaw law(0.5, 0.2);
  for (int trial = 0; trial < 20; ++trial) {
    ControlProblem& p = three_.Build(three_.RandomPhi(), three_.RandomSop(), kPaperTarget);
    ControlVector delta;
    ASSERT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kOk);
    const Eigen::Matrix3d j = p.kinematics.jacobian;
    const Eigen::Vector3d expected =
        0.5 * (j + 0.2 * Eigen::Matrix3d::Identity()).inverse() * p.PointError();
    EXPECT_LT((Eigen::Vector3d(delta) - expected).norm(), 1e-12 * std::max(1.0, expected.norm()));
  }
  EXPECT_THROW(DampedJacobianLaw(0.5, -1.0), std::invalid_argument);
}

TEST_F(JacobianLawsTest, PseudoInverseMatchesSvd) {
  PseudoInverseLaw law(0.1);
  for (ControlFixture* f : {&three_, &four_}) {
    for (int trial = 0; trial < 30; ++trial) {
      ControlProblem& p = f->Build(f->RandomPhi(), f->RandomSop(), kPaperTarget);
      ControlVector delta;
      ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
      const Eigen::VectorXd expected =
          0.1 * SvdPseudoInverse(f->FullTaskJacobian()) * f->FullTaskError();
      EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-10 * std::max(1.0, expected.norm()));
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(f->FullTaskJacobian());
      EXPECT_NEAR(law.diagnostics().singular_values.max(), svd.singularValues()[0], 1e-12);
      EXPECT_NEAR(law.diagnostics().singular_values.min(), svd.singularValues()[1], 1e-10);
    }
  }
}

TEST_F(JacobianLawsTest, PseudoInverseReportsRankDeficiency) {
  // S_in on the first stage's axis zeroes J's first column; with "1" alone, J = 0 at S_in = S1.
  ControlFixture one("1");
  PseudoInverseLaw law(0.1);
  ControlProblem& p = one.Build(one.RandomPhi(), StokesVector::UnitX(), kPaperTarget);
  ControlVector delta;
  EXPECT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kRankDeficient);
  EXPECT_EQ(law.diagnostics().rank, 0);
  EXPECT_EQ(delta.norm(), 0.0);
}

TEST_F(JacobianLawsTest, RegularizedLeastSquaresMatchesThePapersFormula) {
  const double lambda = 0.01;
  RegularizedLeastSquaresLaw law(0.2, lambda);
  for (int trial = 0; trial < 20; ++trial) {
    ControlProblem& p = four_.Build(four_.RandomPhi(), four_.RandomSop(), kPaperTarget);
    ControlVector delta;
    ASSERT_EQ(law.ComputeUpdate(p, &delta), ControlStatus::kOk);
    const Eigen::MatrixXd j = four_.FullTaskJacobian();
    const Eigen::VectorXd expected =
        0.2 * j.transpose() * (j * j.transpose() + lambda * Eigen::Matrix3d::Identity()).inverse() *
        four_.FullTaskError();
    EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-12);
  }
  EXPECT_THROW(RegularizedLeastSquaresLaw(0.2, 0.0), std::invalid_argument);
}

TEST_F(JacobianLawsTest, SetTargetsUseTheOneDimensionalTask) {
  const Target set = Target::Set(Vector3::UnitZ(), 0.0);
  PseudoInverseLaw pinv(1.0);
  ControlProblem& p = four_.Build(four_.RandomPhi(), four_.RandomSop(), set);
  ControlVector delta;
  ASSERT_EQ(pinv.ComputeUpdate(p, &delta), ControlStatus::kOk);
  const Eigen::VectorXd expected = SvdPseudoInverse(four_.FullTaskJacobian()) * four_.FullTaskError();
  EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-12);
}

TEST_F(JacobianLawsTest, ConstructorsRejectBadSteps) {
  EXPECT_THROW(PseudoInverseLaw(0.0), std::invalid_argument);
  EXPECT_THROW(TransposeJacobianLaw(-1.0), std::invalid_argument);
  EXPECT_THROW(InverseJacobianLaw(NAN), std::invalid_argument);
  EXPECT_THROW(PseudoInverseLaw(0.1, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
