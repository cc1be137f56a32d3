#include "dpc/optics/lanes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace dpc {
namespace {

TEST(LanesTest, ArithmeticIsLaneByLane) {
  const Lanes a = {1.0, -2.0, 3.0, -4.0}, b = {0.5, 0.25, -1.0, 2.0}, c = Splat(1.0);
  const std::array<double, 4> sum = ToArray(a + b), product = ToArray(a * b);
  const std::array<double, 4> fused = ToArray(MulAdd(a, b, c));
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(sum[i], a[i] + b[i]);
    EXPECT_EQ(product[i], a[i] * b[i]);
    EXPECT_EQ(fused[i], MulAdd(a[i], b[i], c[i]));  // the scalar MulAdd's bits
  }
  EXPECT_EQ(ToArray(Abs(a)), (std::array<double, 4>{1.0, 2.0, 3.0, 4.0}));
  EXPECT_EQ(ToArray(Abs(Splat(-0.0)))[2], 0.0);
  EXPECT_FALSE(std::signbit(ToArray(Abs(Splat(-0.0)))[2]));
}

TEST(LanesTest, MaxAndSumOfTheLanes) {
  EXPECT_EQ(MaxLane(Lanes{1.0, 7.0, -3.0, 6.5}), 7.0);
  EXPECT_EQ(MaxLane(Lanes{-1.0, -7.0, -3.0, -6.5}), -1.0);
  EXPECT_EQ(SumLanes(Lanes{1.0, 2.0, 3.0, 4.0}), 10.0);
  EXPECT_TRUE(std::isnan(SumLanes(Lanes{0.0, 0.0, NAN, 0.0})));
}

TEST(LanesTest, SmallAngleTurnOnLanesEqualsTheScalarTurnInEveryLane) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-kSmallAngleLimit, kSmallAngleLimit);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 1000; ++trial) {
    const Lanes steps = {x(rng), x(rng), x(rng), x(rng)};
    const Lanes theta = {angle(rng), angle(rng), angle(rng), angle(rng)};
    Lanes c, s;
    for (int i = 0; i < 4; ++i) c[i] = std::cos(theta[i]), s[i] = std::sin(theta[i]);
    Lanes c_next, s_next;
    SmallAngleTurn(c, s, steps, [](Lanes a, Lanes b, Lanes d) { return MulAdd(a, b, d); },
                   &c_next, &s_next);
    for (int i = 0; i < 4; ++i) {
      double scalar_c, scalar_s;
      SmallAngleTurn(c[i], s[i], steps[i],
                     [](double a, double b, double d) { return MulAdd(a, b, d); }, &scalar_c,
                     &scalar_s);
      ASSERT_EQ(c_next[i], scalar_c);
      ASSERT_EQ(s_next[i], scalar_s);
    }
  }
}

// Units in the last place of `want` between it and `got` (the spacing of doubles at |want|).
double UlpsFrom(double got, double want) {
  const double spacing = std::nextafter(std::abs(want), INFINITY) - std::abs(want);
  return std::abs(got - want) / spacing;
}

TEST(LanesTest, SinCosIsWithinTwoUlpOfTheLibrary) {
  std::mt19937_64 rng(11);
  double worst_ulp = 0.0, worst_abs = 0.0;
  // Around zero, the pose's usual range, and out to the reduction's limit.
  for (const double range : {1e-3, 1.0, 4.0, 40.0, 4e3, 0.99 * kLanesSinCosLimit}) {
    std::uniform_real_distribution<double> x(-range, range);
    for (int trial = 0; trial < 50000; ++trial) {
      const Lanes angles = {x(rng), x(rng), x(rng), x(rng)};
      Lanes s, c;
      SinCos(angles, &s, &c);
      for (int i = 0; i < 4; ++i) {
        const double want_s = std::sin(angles[i]), want_c = std::cos(angles[i]);
        worst_abs = std::max({worst_abs, std::abs(s[i] - want_s), std::abs(c[i] - want_c)});
        // Relative to values not near a zero (there the absolute error is what counts).
        if (std::abs(want_s) > 1e-3) worst_ulp = std::max(worst_ulp, UlpsFrom(s[i], want_s));
        if (std::abs(want_c) > 1e-3) worst_ulp = std::max(worst_ulp, UlpsFrom(c[i], want_c));
      }
    }
  }
  EXPECT_LE(worst_ulp, 2.0);
  EXPECT_LE(worst_abs, 2.3e-16);  // one ulp of 1
  // Exact where the library is: zero, and the quadrant boundaries' signs.
  Lanes s, c;
  SinCos(Lanes{0.0, M_PI / 2, -M_PI / 2, M_PI}, &s, &c);
  EXPECT_EQ(s[0], 0.0);
  EXPECT_EQ(c[0], 1.0);
  EXPECT_EQ(s[1], 1.0);
  EXPECT_EQ(s[2], -1.0);
  EXPECT_EQ(c[3], -1.0);
  EXPECT_NEAR(c[1], std::cos(M_PI / 2), 1e-25);
  EXPECT_NEAR(s[3], std::sin(M_PI), 1e-25);
}

TEST(LanesTest, SinCosBeyondTheReductionAndNonFiniteLanesTakeTheLibrary) {
  const Lanes angles = {2.0 * kLanesSinCosLimit, -1e300, NAN, INFINITY};
  Lanes s, c;
  SinCos(angles, &s, &c);
  EXPECT_EQ(s[0], std::sin(angles[0]));
  EXPECT_EQ(c[0], std::cos(angles[0]));
  EXPECT_EQ(s[1], std::sin(angles[1]));
  EXPECT_EQ(c[1], std::cos(angles[1]));
  for (int i = 2; i < 4; ++i) {
    EXPECT_TRUE(std::isnan(s[i])) << i;
    EXPECT_TRUE(std::isnan(c[i])) << i;
  }
}

}  // namespace
}  // namespace dpc
