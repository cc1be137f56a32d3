#include "dpc/control/task_pseudo_inverse.h"

#include <gtest/gtest.h>

#include <random>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::SvdPseudoInverse;

class TaskPseudoInverseTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{5};
  std::normal_distribution<double> normal_;

  TaskJacobian Random(int rows, int cols) {
    TaskJacobian a(rows, cols);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < cols; ++j) a(i, j) = normal_(rng_);
    return a;
  }
  ControlVector RandomVector(int n) {
    ControlVector v(n);
    for (int i = 0; i < n; ++i) v[i] = normal_(rng_);
    return v;
  }
  // x = A⁺e and (I − A⁺A)v against the SVD reference.
  void ExpectMatchesSvd(const TaskJacobian& a, double tolerance) {
    TaskPseudoInverse pinv;
    pinv.Compute(a);
    const Eigen::MatrixXd reference = SvdPseudoInverse(Eigen::MatrixXd(a));
    TaskVector e(a.rows());
    for (int i = 0; i < e.size(); ++i) e[i] = normal_(rng_);
    ControlVector x;
    pinv.Solve(e, &x);
    const Eigen::VectorXd expected = reference * Eigen::VectorXd(e);
    EXPECT_LT((Eigen::VectorXd(x) - expected).norm(), tolerance * std::max(1.0, expected.norm()));
    const ControlVector v = RandomVector(static_cast<int>(a.cols()));
    ControlVector projected;
    pinv.NullSpaceProjection(v, &projected);
    const Eigen::MatrixXd p =
        Eigen::MatrixXd::Identity(a.cols(), a.cols()) - reference * Eigen::MatrixXd(a);
    EXPECT_LT((Eigen::VectorXd(projected) - p * Eigen::VectorXd(v)).norm(), tolerance);
  }
};

TEST_F(TaskPseudoInverseTest, MatchesSvdForRandomTwoRowTasks) {
  for (int n : {2, 3, 4, 7, 16, 32}) {
    for (int trial = 0; trial < 20; ++trial) ExpectMatchesSvd(Random(2, n), 1e-12);
  }
}

TEST_F(TaskPseudoInverseTest, MatchesSvdForOneRowTasks) {
  for (int n : {1, 3, 4, 16}) ExpectMatchesSvd(Random(1, n), 1e-13);
}

TEST_F(TaskPseudoInverseTest, SingularValuesMatchSvd) {
  for (int trial = 0; trial < 20; ++trial) {
    const TaskJacobian a = Random(2, 4);
    TaskPseudoInverse pinv;
    pinv.Compute(a);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
    EXPECT_NEAR(pinv.sigma_max(), svd.singularValues()[0], 1e-12);
    EXPECT_NEAR(pinv.sigma_min(), svd.singularValues()[1], 1e-12);
    EXPECT_EQ(pinv.rank(), 2);
  }
}

TEST_F(TaskPseudoInverseTest, NearlySingularKeepsRelativeAccuracyOfSigmaMin) {
  // Rows nearly parallel: σ2/σ1 ≈ 1e-9. A perturbation of A by ε‖A‖ moves σ2 and v2 by
  // ~ε‖A‖/σ2 ≈ 1e-7 relative (the gap to the zero singular values is σ2), for any algorithm;
  // inverting AAᵀ instead would lose everything (κ² ≈ 1e18).
  TaskJacobian a(2, 4);
  a << 1.0, 2.0, -0.5, 0.3,  //
      1.0, 2.0, -0.5, 0.3;
  a(1, 3) += 1e-9;
  TaskPseudoInverse pinv;
  pinv.Compute(a);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
  EXPECT_NEAR(pinv.sigma_min() / svd.singularValues()[1], 1.0, 1e-6);
  EXPECT_EQ(pinv.rank(), 2);
  ExpectMatchesSvd(a, 1e-5);
}

TEST_F(TaskPseudoInverseTest, RankOneAndZeroAreHandledLikeSvd) {
  TaskJacobian a(2, 3);
  a << 1.0, -2.0, 0.5,  //
      2.0, -4.0, 1.0;   // rank 1
  TaskPseudoInverse pinv;
  pinv.Compute(a);
  EXPECT_EQ(pinv.rank(), 1);
  EXPECT_NEAR(pinv.sigma_min(), 0.0, 1e-12);
  ExpectMatchesSvd(a, 1e-12);

  TaskJacobian zero = TaskJacobian::Zero(2, 3);
  pinv.Compute(zero);
  EXPECT_EQ(pinv.rank(), 0);
  TaskVector e(2);
  e << 1.0, 2.0;
  ControlVector x;
  pinv.Solve(e, &x);
  EXPECT_EQ(x.norm(), 0.0);
}

TEST_F(TaskPseudoInverseTest, NullSpaceProjectionIsAnIdempotentProjectorOntoNullA) {
  const TaskJacobian a = Random(2, 4);
  TaskPseudoInverse pinv;
  pinv.Compute(a);
  const ControlVector v = RandomVector(4);
  ControlVector p, pp;
  pinv.NullSpaceProjection(v, &p);
  pinv.NullSpaceProjection(p, &pp);
  EXPECT_LT((a * p).norm(), 1e-13);
  EXPECT_LT((p - pp).norm(), 1e-13);
}

}  // namespace
}  // namespace dpc
