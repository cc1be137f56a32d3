#include "dpc/optics/lanes.h"

#include <gtest/gtest.h>

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

TEST(LanesTest, SmallAngleSinCosFusedEqualsTheScalarSeriesInEveryLane) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-kSmallAngleLimit, kSmallAngleLimit);
  for (int trial = 0; trial < 1000; ++trial) {
    const Lanes angles = {x(rng), x(rng), x(rng), x(rng)};
    Lanes s, c;
    SmallAngleSinCosFused(angles, &s, &c);
    for (int i = 0; i < 4; ++i) {
      double scalar_s, scalar_c;
      SmallAngleSinCosFused(angles[i], &scalar_s, &scalar_c);
      ASSERT_EQ(s[i], scalar_s);
      ASSERT_EQ(c[i], scalar_c);
    }
  }
}

}  // namespace
}  // namespace dpc
