#include "dpc/optics/rotation.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dpc {
namespace {

constexpr double kTol = 1e-14;

class RotationTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{42};
  std::normal_distribution<double> normal_;
  std::uniform_real_distribution<double> angle_{-10.0, 10.0};

  Vector3 RandomUnit() { return Vector3(normal_(rng_), normal_(rng_), normal_(rng_)).normalized(); }
};

TEST_F(RotationTest, ElementalRotationsAreOrthogonalWithDeterminantOne) {
  for (int i = 0; i < 200; ++i) {
    const double theta = angle_(rng_);
    for (const Matrix3& m : {R1(theta), R2(theta), R3(theta)}) {
      EXPECT_LT((m * m.transpose() - Matrix3::Identity()).norm(), kTol);
      EXPECT_NEAR(m.determinant(), 1.0, kTol);
    }
  }
}

TEST_F(RotationTest, ElementalRotationsFollowTheRightHandRule) {
  // A quarter turn about S1 takes S2 to S3; about S2 takes S3 to S1; about S3 takes S1 to S2.
  EXPECT_LT((R1(M_PI / 2) * Vector3::UnitY() - Vector3::UnitZ()).norm(), kTol);
  EXPECT_LT((R2(M_PI / 2) * Vector3::UnitZ() - Vector3::UnitX()).norm(), kTol);
  EXPECT_LT((R3(M_PI / 2) * Vector3::UnitX() - Vector3::UnitY()).norm(), kTol);
}

TEST_F(RotationTest, GeneralRotationMatchesElementalOnTheAxes) {
  for (int i = 0; i < 100; ++i) {
    const double theta = angle_(rng_);
    EXPECT_LT((RotationAboutAxis(Vector3::UnitX(), theta) - R1(theta)).norm(), kTol);
    EXPECT_LT((RotationAboutAxis(Vector3::UnitY(), theta) - R2(theta)).norm(), kTol);
    EXPECT_LT((RotationAboutAxis(Vector3::UnitZ(), theta) - R3(theta)).norm(), kTol);
  }
}

TEST_F(RotationTest, GeneralRotationIsOrthogonalAndFixesItsAxis) {
  for (int i = 0; i < 200; ++i) {
    const Vector3 r = RandomUnit();
    const double theta = angle_(rng_);
    const Matrix3 m = RotationAboutAxis(r, theta);
    EXPECT_LT((m * m.transpose() - Matrix3::Identity()).norm(), 1e-13);
    EXPECT_NEAR(m.determinant(), 1.0, 1e-13);
    EXPECT_LT((m * r - r).norm(), 1e-13);
    // The rotation angle: trace = 1 + 2 cos θ.
    EXPECT_NEAR(m.trace(), 1.0 + 2.0 * std::cos(theta), 1e-13);
  }
}

TEST_F(RotationTest, DerivativeIsCrossProductTimesRotation) {
  // Paper eq. 8: dM/dθ = [r×] M.
  const double h = 1e-5;  // truncation h²/6 ≈ 2e-11, round-off ≈ ε·|θ|/h ≈ 2e-10
  for (int i = 0; i < 50; ++i) {
    const Vector3 r = RandomUnit();
    const double theta = angle_(rng_);
    const Matrix3 numeric =
        (RotationAboutAxis(r, theta + h) - RotationAboutAxis(r, theta - h)) / (2 * h);
    EXPECT_LT((numeric - CrossProductMatrix(r) * RotationAboutAxis(r, theta)).norm(), 2e-9);
  }
}

TEST_F(RotationTest, RotateVectorMatchesTheMatrix) {
  for (int i = 0; i < 200; ++i) {
    const Vector3 r = RandomUnit(), v = RandomUnit();
    const double theta = angle_(rng_);
    EXPECT_LT((RotateVector(r, std::cos(theta), std::sin(theta), v) -
               RotationAboutAxis(r, theta) * v).norm(),
              1e-14);
  }
}

TEST_F(RotationTest, CrossProductMatrixComputesTheCrossProduct) {
  const Vector3 r = RandomUnit(), v = RandomUnit();
  EXPECT_LT((CrossProductMatrix(r) * v - r.cross(v)).norm(), kTol);
}

TEST_F(RotationTest, SinCosMatchesTheLibraryInsideAndOutsideTheSeriesRange) {
  for (double x : {0.0, 1e-300, -1e-12, 3e-5, -0.0078, 0.0078124, 0.0078125, 0.1, -3.0, 100.0}) {
    double s, c;
    SinCos(x, &s, &c);
    EXPECT_NEAR(s, std::sin(x), 2e-16 * std::max(1.0, std::abs(std::sin(x)))) << x;
    EXPECT_NEAR(c, std::cos(x), 4.5e-16) << x;  // 2 ulp of 1
  }
}

TEST_F(RotationTest, MulAddIsAProductPlusASum) {
  EXPECT_EQ(MulAdd(3.0, 4.0, 5.0), 17.0);
  EXPECT_EQ(MulAdd(-0.5, 8.0, 4.0), 0.0);
  // Rounded once with FMA, twice without: within one rounding of the exact value either way.
  const double a = 1.0 + 0x1p-30, b = 1.0 - 0x1p-30;
  EXPECT_NEAR(MulAdd(a, b, -1.0), -0x1p-60, 0x1p-52);
#ifdef __FMA__
  EXPECT_EQ(MulAdd(a, b, -1.0), -0x1p-60);  // the exact product survives the fused operation
#endif
  EXPECT_TRUE(std::isnan(MulAdd(NAN, 1.0, 1.0)));
}

TEST_F(RotationTest, SmallAngleTurnIsTheAngleAdditionToAboutOneUlp) {
  std::uniform_real_distribution<double> x(-kSmallAngleLimit, kSmallAngleLimit);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  const auto mul_add = [](double a, double b, double c) { return MulAdd(a, b, c); };
  double worst_cos = 0.0, worst_sin = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double theta = angle(rng_), step = x(rng_);
    const double c = std::cos(theta), s = std::sin(theta);
    double c_next, s_next;
    SmallAngleTurn(c, s, step, mul_add, &c_next, &s_next);
    // The exact angle addition of the given c, s (long double: 64-bit mantissa).
    const long double cx = std::cos(static_cast<long double>(step));
    const long double sx = std::sin(static_cast<long double>(step));
    const long double want_cos = c * cx - s * sx, want_sin = s * cx + c * sx;
    worst_cos = std::max(worst_cos, static_cast<double>(std::abs(c_next - want_cos)));
    worst_sin = std::max(worst_sin, static_cast<double>(std::abs(s_next - want_sin)));
  }
  EXPECT_LT(worst_cos, 2.3e-16);  // 1 ulp of 1
  EXPECT_LT(worst_sin, 2.3e-16);
  double c_next, s_next;
  SmallAngleTurn(0.6, 0.8, 0.0, mul_add, &c_next, &s_next);  // no step: the pose unchanged
  EXPECT_EQ(c_next, 0.6);
  EXPECT_EQ(s_next, 0.8);
}

TEST_F(RotationTest, SmallArcSineIsExactToAboutOneUlpUpToItsLimit) {
  std::uniform_real_distribution<double> x(-kSmallArcSineLimit, kSmallArcSineLimit);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double v = x(rng_);
    if (v == 0.0) continue;
    worst = std::max(worst, std::abs(SmallArcSine(v) - std::asin(v)) / std::abs(std::asin(v)));
  }
  EXPECT_LT(worst, 4.5e-16);  // 2 ulp
  EXPECT_EQ(SmallArcSine(0.0), 0.0);
  EXPECT_NEAR(SmallArcSine(kSmallArcSineLimit), std::asin(kSmallArcSineLimit), 1e-16);
}

TEST_F(RotationTest, AxisClassification) {
  EXPECT_EQ(ClassifyAxis(Vector3::UnitX()), ElementalAxis::kS1);
  EXPECT_EQ(ClassifyAxis(Vector3::UnitY()), ElementalAxis::kS2);
  EXPECT_EQ(ClassifyAxis(Vector3::UnitZ()), ElementalAxis::kS3);
  EXPECT_EQ(ClassifyAxis(-Vector3::UnitZ()), ElementalAxis::kGeneral);
  EXPECT_EQ(ElementalAxisVector(ElementalAxis::kS2), Vector3::UnitY());
  EXPECT_THROW(ElementalAxisVector(ElementalAxis::kGeneral), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
