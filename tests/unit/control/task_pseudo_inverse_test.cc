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

namespace dpc {
namespace {

// Reference: A_λ⁺ = Σ σ_i/(σ_i² + λ²) v_i u_iᵀ and I − A_λ⁺A from an SVD.
void ExpectMatchesDampedSvd(const TaskJacobian& a, double max_damping, double threshold,
                            double tolerance) {
  TaskPseudoInverse pinv;
  pinv.ComputeDamped(a, max_damping, threshold);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(a),
                                        Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd s = svd.singularValues();
  const double sigma_min = s[s.size() - 1];
  const double lambda_squared =
      sigma_min < threshold
          ? max_damping * max_damping * (1.0 - sigma_min * sigma_min / (threshold * threshold))
          : 0.0;
  EXPECT_NEAR(pinv.damping_squared(), lambda_squared, 1e-12);
  Eigen::MatrixXd reference = Eigen::MatrixXd::Zero(a.cols(), a.rows());
  for (int i = 0; i < s.size(); ++i) {
    const double denominator = s[i] * s[i] + lambda_squared;
    if (denominator > 0.0) {
      reference += (s[i] / denominator) * svd.matrixV().col(i) * svd.matrixU().col(i).transpose();
    }
  }
  TaskVector e(a.rows());
  for (int i = 0; i < e.size(); ++i) e[i] = 0.3 + i;
  ControlVector x;
  pinv.Solve(e, &x);
  const Eigen::VectorXd expected = reference * Eigen::VectorXd(e);
  EXPECT_LT((Eigen::VectorXd(x) - expected).norm(), tolerance * std::max(1.0, expected.norm()));
  ControlVector v(a.cols()), projected;
  for (int i = 0; i < v.size(); ++i) v[i] = 1.0 - 0.4 * i;
  pinv.NullSpaceProjection(v, &projected);
  const Eigen::MatrixXd p =
      Eigen::MatrixXd::Identity(a.cols(), a.cols()) - reference * Eigen::MatrixXd(a);
  EXPECT_LT((Eigen::VectorXd(projected) - p * Eigen::VectorXd(v)).norm(), tolerance);
}

TEST(TaskPseudoInverseDampingTest, AboveTheThresholdItIsTheUndampedInverse) {
  TaskJacobian a(2, 4);
  a << 1.0, 2.0, -0.5, 0.3,  //
      -0.2, 0.4, 1.5, 0.9;
  ExpectMatchesDampedSvd(a, 0.5, 0.1, 1e-12);
  TaskPseudoInverse plain, damped;
  plain.Compute(a);
  damped.ComputeDamped(a, 0.5, 0.1);
  EXPECT_EQ(damped.damping_squared(), 0.0);
}

TEST(TaskPseudoInverseDampingTest, MatchesTheDampedSvdNearAConstructedSingularity) {
  // Rows nearly parallel: σ2 from 1e-1 down to 0 (both the normal-equation and Jacobi paths).
  for (double gap : {1e-1, 1e-2, 1e-4, 1e-8, 0.0}) {
    TaskJacobian a(2, 4);
    a << 1.0, 2.0, -0.5, 0.3,  //
        1.0, 2.0, -0.5, 0.3;
    a(1, 3) += gap;
    a(1, 0) -= 0.5 * gap;
    ExpectMatchesDampedSvd(a, 0.5, 0.5, 1e-9);
  }
}

TEST(TaskPseudoInverseDampingTest, OneRowTaskIsDampedBelowTheThreshold) {
  TaskJacobian a(1, 3);
  a << 0.1, -0.05, 0.02;
  ExpectMatchesDampedSvd(a, 0.4, 0.5, 1e-12);
  a << 1.0, -0.5, 0.2;
  ExpectMatchesDampedSvd(a, 0.4, 0.5, 1e-12);
}

TEST(TaskPseudoInverseDampingTest, TheStepVanishesWithSigmaInsteadOfGrowing) {
  // Undamped, the step along the vanishing direction is 1/σ2 per unit error. Damped with
  // λ0 = ε, σ2² + λ² = ε² and the step is σ2/ε²: it goes to 0 with σ2.
  TaskVector e(2);
  e << 0.0, 1.0;
  for (double gap : {1e-2, 1e-3, 1e-4, 1e-6}) {
    TaskJacobian a(2, 3);
    a << 1.0, 0.0, 0.0,  //
        0.0, gap, 0.0;
    TaskPseudoInverse pinv;
    pinv.ComputeDamped(a, 0.5, 0.5);
    ControlVector x;
    pinv.Solve(e, &x);
    EXPECT_NEAR(x.norm(), gap / 0.25, 1e-12);
    pinv.Compute(a);
    pinv.Solve(e, &x);
    EXPECT_NEAR(x.norm(), 1.0 / gap, 1e-6 / gap);
  }
}

}  // namespace
}  // namespace dpc
