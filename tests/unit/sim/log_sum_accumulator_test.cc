#include "dpc/sim/log_sum_accumulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace dpc {
namespace {

// Σ ln x, summed in long double as the reference.
long double Reference(const std::vector<double>& x) {
  long double sum = 0;
  for (double v : x) sum += std::log(static_cast<long double>(v));
  return sum;
}

TEST(LogSumAccumulatorTest, MatchesTheSumOfLogarithms) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> exponent(-20.0, 0.0);
  std::vector<double> x(100003);
  for (auto& v : x) v = std::pow(10.0, exponent(rng));
  LogSumAccumulator acc;
  for (size_t i = 0; i < x.size(); i += 256) {
    acc.AddBatch(x.data() + i, static_cast<int>(std::min<size_t>(256, x.size() - i)));
  }
  EXPECT_EQ(acc.count(), 100003);
  const long double expected = Reference(x);
  EXPECT_NEAR(acc.LogSum() / static_cast<double>(expected), 1.0, 1e-13);
}

TEST(LogSumAccumulatorTest, ExtremesNeitherUnderflowNorOverflow) {
  std::vector<double> tiny(1000, LogSumAccumulator::kMinValue);
  std::vector<double> huge(1000, LogSumAccumulator::kMaxValue);
  LogSumAccumulator a, b;
  a.AddBatch(tiny.data(), 1000);
  b.AddBatch(huge.data(), 1000);
  EXPECT_NEAR(a.LogSum() / (1000 * std::log(1e-30)), 1.0, 1e-13);
  EXPECT_NEAR(b.LogSum() / (1000 * std::log(1e30)), 1.0, 1e-13);
}

TEST(LogSumAccumulatorTest, OddBatchSizesAndEmpty) {
  LogSumAccumulator acc;
  EXPECT_EQ(acc.LogSum(), 0.0);
  const double values[] = {0.5, 0.25, 2.0, 8.0, 0.125, 3.0, 7.0};
  for (int n : {1, 2, 3, 1}) acc.AddBatch(values, n);
  const double expected = std::log(0.5) + (std::log(0.5) + std::log(0.25)) +
                          (std::log(0.5) + std::log(0.25) + std::log(2.0)) + std::log(0.5);
  EXPECT_NEAR(acc.LogSum(), expected, 1e-14);
  EXPECT_EQ(acc.count(), 7);
}

}  // namespace
}  // namespace dpc
