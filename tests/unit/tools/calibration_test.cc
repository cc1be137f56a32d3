#include "calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "dpc/optics/rotation.h"

namespace dpc::tools {
namespace {

TEST(CalibrationTest, FitRotationRecoversARotationFromMovingInputs) {
  const Matrix3 truth = RotationAboutAxis(Vector3(1, 2, -0.5).normalized(), 2.2);
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  std::vector<StokesVector> in, out;
  for (int k = 0; k < 12; ++k) {
    const StokesVector s = StokesVector(normal(random), normal(random), normal(random)).normalized();
    in.push_back(s);
    out.push_back(truth * s);
  }
  double spread = 0;
  const Matrix3 fitted = FitRotation(in, out, &spread);
  EXPECT_LT((fitted - truth).norm(), 1e-12);
  EXPECT_GT(spread, 0.2);
  EXPECT_NEAR(fitted.determinant(), 1.0, 1e-12);
  // Inputs on one line do not determine it: the spread says so.
  const std::vector<StokesVector> same(5, StokesVector::UnitX());
  std::vector<StokesVector> images(5, truth * StokesVector::UnitX());
  FitRotation(same, images, &spread);
  EXPECT_LT(spread, 1e-9);
  EXPECT_THROW(FitRotation({StokesVector::UnitX()}, {StokesVector::UnitX()}, nullptr), std::invalid_argument);
}

TEST(CalibrationTest, TheSignedAngleAboutAFixedAxisUnwrapsBeyondHalfATurn) {
  const Vector3 axis = Vector3(0.3, -0.2, 0.9).normalized();
  std::vector<double> angles;
  for (int k = 0; k <= 40; ++k) {
    const double truth = -7.0 + 0.4 * k;  // −7 … 9 rad: more than two turns
    angles.push_back(SignedAngleAbout(RotationAboutAxis(axis, truth), axis));
  }
  Unwrap(&angles);
  for (int k = 0; k <= 40; ++k) EXPECT_NEAR(angles[static_cast<size_t>(k)] - angles[0], 0.4 * k, 1e-9) << k;
  const auto found = RotationAxis(RotationAboutAxis(axis, 1.0));
  ASSERT_TRUE(found.has_value());
  EXPECT_NEAR(std::abs(found->dot(axis)), 1.0, 1e-12);
  EXPECT_FALSE(RotationAxis(RotationAboutAxis(axis, 0.05)).has_value());
}

TEST(CalibrationTest, APolynomialFitReproducesACubicAndItsSlope) {
  std::vector<double> x, y;
  for (int k = 0; k <= 20; ++k) {
    x.push_back(-10.0 + k);
    y.push_back(0.55 * x.back() + 0.0012 * std::pow(x.back(), 3));
  }
  const ScaledPolynomial p = FitPolynomial(x, y, 5);
  EXPECT_NEAR(p(3.3), 0.55 * 3.3 + 0.0012 * std::pow(3.3, 3), 1e-9);
  EXPECT_NEAR(p.Derivative(2.0), 0.55 + 3 * 0.0012 * 4.0, 1e-9);
  EXPECT_THROW(FitPolynomial({1.0, 2.0}, {1.0, 2.0}, 3), std::invalid_argument);
}

}  // namespace
}  // namespace dpc::tools
