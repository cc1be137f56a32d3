#include "dpc/disturbance/polarimeter_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

class PolarimeterNoiseTest : public ::testing::Test {
 protected:
  RandomSource inputs_{5, 0};  // random true SOPs
};

TEST_F(PolarimeterNoiseTest, ZeroSigmaReturnsTheInputExactly) {
  PolarimeterNoise noise(0.0, 1);
  for (int i = 0; i < 100; ++i) {
    const StokesVector s = inputs_.UnitVector();
    EXPECT_EQ(noise.Measure(s), s);
  }
}

TEST_F(PolarimeterNoiseTest, AngularErrorIsRayleighWithScaleSigma) {
  constexpr double kSigmaDeg = 0.5;
  constexpr int kSamples = 200000;
  PolarimeterNoise noise(kSigmaDeg, 1);
  const double sigma = kSigmaDeg * M_PI / 180.0;
  EXPECT_DOUBLE_EQ(noise.sigma_rad(), sigma);
  double sum = 0, sum2 = 0;
  Vector3 tangent_sum = Vector3::Zero();
  for (int i = 0; i < kSamples; ++i) {
    const StokesVector s = inputs_.UnitVector();
    const StokesVector measured = noise.Measure(s);
    const double error = SphereAngleRad(s, measured);
    sum += error;
    sum2 += error * error;
    Vector3 e1, e2;
    TangentBasis(s, &e1, &e2);
    tangent_sum += Vector3(e1.dot(measured), e2.dot(measured), 0.0);
  }
  const double n = kSamples;
  // Rayleigh(σ): mean σ√(π/2), standard deviation σ√((4 − π)/2) ≈ 0.655σ (SE 0.15 % of the
  // mean); E[error²] = 2σ², SE 2σ²/√n.
  EXPECT_NEAR(sum / n / (sigma * std::sqrt(M_PI / 2)), 1.0,
              6.0 * std::sqrt((4.0 - M_PI) / 2) / std::sqrt(M_PI / 2) / std::sqrt(n));
  EXPECT_NEAR(sum2 / n / (2.0 * sigma * sigma), 1.0, 6.0 / std::sqrt(n));
  // No preferred direction: the mean tangent displacement is ≈ 0 (SE σ/√n per component).
  EXPECT_NEAR(tangent_sum.x() / n, 0.0, 6.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(tangent_sum.y() / n, 0.0, 6.0 * sigma / std::sqrt(n));
}

TEST_F(PolarimeterNoiseTest, OutputIsUnitEverywhereIncludingThePoles) {
  PolarimeterNoise noise(3.0, 1);
  // TangentBasis switches branch on the sign of s3; −0 takes the southern branch.
  const StokesVector poles[] = {StokesVector(0.0, 0.0, 1.0), StokesVector(0.0, 0.0, -1.0),
                                StokesVector(1.0, 0.0, -0.0), StokesVector(0.0, 1.0, 0.0)};
  for (const StokesVector& pole : poles) {
    for (int i = 0; i < 100; ++i) EXPECT_NEAR(noise.Measure(pole).norm(), 1.0, 1e-15);
  }
  for (int i = 0; i < 10000; ++i) {
    ASSERT_NEAR(noise.Measure(inputs_.UnitVector()).norm(), 1.0, 1e-15);
  }
}

TEST_F(PolarimeterNoiseTest, IsTheDocumentedFormulaOnStreamTwo) {
  constexpr double kSigmaDeg = 2.0;
  PolarimeterNoise noise(kSigmaDeg, 9);
  RandomSource random(9, 2);
  const double sigma = kSigmaDeg * M_PI / 180.0;
  for (int i = 0; i < 100; ++i) {
    const StokesVector s = inputs_.UnitVector();
    Vector3 e1, e2;
    TangentBasis(s, &e1, &e2);
    const double n1 = random.Normal(), n2 = random.Normal();
    const Vector3 v = sigma * (n1 * e1 + n2 * e2);
    const StokesVector expected = s * std::cos(v.norm()) + v.normalized() * std::sin(v.norm());
    EXPECT_LT((noise.Measure(s) - expected).norm(), 1e-15);
  }
}

TEST_F(PolarimeterNoiseTest, SameSeedSameReadings) {
  PolarimeterNoise a(1.0, 3), b(1.0, 3), c(1.0, 4);
  const StokesVector s(0.0, 0.6, 0.8);
  int equal_other_seed = 0;
  for (int i = 0; i < 1000; ++i) {
    const StokesVector reading = a.Measure(s);
    ASSERT_EQ(reading, b.Measure(s));
    equal_other_seed += (reading == c.Measure(s));
  }
  EXPECT_EQ(equal_other_seed, 0);
}

TEST_F(PolarimeterNoiseTest, RejectsNegativeSigma) {
  EXPECT_THROW(PolarimeterNoise(-0.1, 1), std::invalid_argument);
}

TEST_F(PolarimeterNoiseTest, RejectsNonFiniteSigma) {
  EXPECT_THROW(PolarimeterNoise(NAN, 1), std::invalid_argument);
}

}  // namespace
}  // namespace dpc

namespace dpc {
namespace {

TEST(PolarimeterNoiseStreamTest, TwoPolarimetersWithOneSeedDrawIndependently) {
  PolarimeterNoise input(0.5, 7, 2), output(0.5, 7, 3), input_again(0.5, 7, 2);
  const StokesVector s(0, 0.6, 0.8);
  const StokesVector a = input.Measure(s), b = output.Measure(s), c = input_again.Measure(s);
  EXPECT_NE(a, b);
  EXPECT_EQ(a, c);
}

}  // namespace
}  // namespace dpc
