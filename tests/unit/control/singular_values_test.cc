#include "dpc/control/singular_values.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dpc {
namespace {

TEST(SingularValuesTest, FromTheGramMatrixOfATwoRowMatrix) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Matrix<double, 2, 4> a;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 4; ++j) a(i, j) = normal(rng);
    const Eigen::Matrix2d g = a * a.transpose();
    const SingularValues s =
        SingularValues::FromGram(g(0, 0), g(1, 1), g(0, 1), g.determinant());
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
    EXPECT_NEAR(s.max(), svd.singularValues()[0], 1e-12);
    EXPECT_NEAR(s.min(), svd.singularValues()[1], 1e-12);
    EXPECT_NEAR(s.min_squared(), std::pow(svd.singularValues()[1], 2), 1e-11);
  }
}

TEST(SingularValuesTest, LowerBoundAndNearSingularTestAgreeWithTheValues) {
  std::mt19937_64 rng(12);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix<double, 2, 4> a;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 4; ++j) a(i, j) = normal(rng);
    a.row(1) += (trial % 7) * a.row(0);  // some nearly parallel rows
    const Eigen::Matrix2d g = a * a.transpose();
    const SingularValues s = SingularValues::FromGram(g(0, 0), g(1, 1), g(0, 1), g.determinant());
    // det/tr ≤ σ_min² ≤ 2·det/tr: MayBeBelow is true for any bound above σ_min² and false for
    // any bound below det/tr.
    EXPECT_TRUE(s.MayBeBelow(s.min_squared() * (1 + 1e-9)));
    EXPECT_FALSE(s.MayBeBelow(0.49 * s.min_squared()));
    for (double ratio : {0.05, 0.1, 0.5}) {
      const double actual = s.min() / s.max();
      if (std::abs(actual - ratio) > 1e-9) {
        EXPECT_EQ(s.IsBelowRatio(ratio), actual < ratio);
      }
    }
  }
  EXPECT_TRUE(SingularValues::Exact(1.0, 0.05).IsBelowRatio(0.1));
  EXPECT_FALSE(SingularValues::FromGram(4.0).IsBelowRatio(0.1));
}

TEST(SingularValuesTest, OneRowAndExactValues) {
  EXPECT_DOUBLE_EQ(SingularValues::FromGram(9.0).max(), 3.0);
  EXPECT_DOUBLE_EQ(SingularValues::FromGram(9.0).min(), 3.0);
  EXPECT_EQ(SingularValues::Exact(2.0, 0.5).max(), 2.0);
  EXPECT_EQ(SingularValues::Exact(2.0, 0.5).min(), 0.5);
  EXPECT_EQ(SingularValues::FromGram(0.0, 0.0, 0.0, 0.0).min(), 0.0);
  EXPECT_EQ(SingularValues().max(), 0.0);
}

}  // namespace
}  // namespace dpc
