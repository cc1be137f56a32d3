// The bench's summary of a period: what a dashboard sees instead of every sample. Bounded at any
// rate, the error to the current target, the loop latency of each newly answered sample, the
// driver's latest state.
#include "dpc/bench/bench_summary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace dpc {
namespace {

TargetConfig PointTarget(const StokesVector& point) {
  TargetConfig t;
  t.kind = TargetConfig::Kind::kPoint;
  t.point = point;
  return t;
}

/// A sample whose S_out is `angle_deg` from [0, 0.6, 0.8], turned towards S1.
BenchSample Sample(uint64_t sequence, double angle_deg) {
  const double a = angle_deg * std::numbers::pi / 180.0;
  BenchSample s;
  s.sequence = sequence;
  s.s_in = StokesVector(1.0, 0.0, 0.0);
  s.s_out = StokesVector(std::sin(a), 0.6 * std::cos(a), 0.8 * std::cos(a));
  return s;
}

DriverState State(uint64_t answers, int64_t sample_publish_ns) {
  DriverState s;
  s.answers_sample = answers;
  s.sample_publish_time_ns = sample_publish_ns;
  s.mode = DriverMode::kActive;
  s.motion = WaveplateMotion::Still(ControlVector::Zero(3));
  return s;
}

TEST(BenchSummaryBuilderTest, ThePeriodsErrorToTheCurrentTargetAndItsSamples) {
  BenchSummaryBuilder builder(PointTarget(StokesVector(0.0, 0.6, 0.8)));
  builder.Take(0, 1);  // starts the first period
  builder.OnSample(Sample(1, 2.0));
  builder.OnSample(Sample(2, 4.0));
  BenchSummary s = builder.Take(50'000'000, 2);
  EXPECT_EQ(s.sequence, 2u);
  EXPECT_DOUBLE_EQ(s.period_s, 0.05);
  EXPECT_EQ(s.samples, 2u);
  EXPECT_EQ(s.last_sample, 2u);
  ASSERT_TRUE(s.error_mean_deg);
  EXPECT_NEAR(*s.error_mean_deg, 3.0, 1e-9);
  EXPECT_NEAR(s.error_max_deg, 4.0, 1e-9);
  EXPECT_FALSE(s.state);

  // A new target counts from then on; an empty period has no error.
  builder.OnTarget(PointTarget(StokesVector(1.0, 0.0, 0.0)));
  EXPECT_FALSE(builder.Take(60'000'000, 3).error_mean_deg);
  builder.OnSample(Sample(3, 90.0));  // S_out = S1: on the new target
  EXPECT_NEAR(*builder.Take(70'000'000, 4).error_mean_deg, 0.0, 1e-6);
}

TEST(BenchSummaryBuilderTest, TheTrailStaysBoundedAtAnyRateSpreadOverThePeriodAndRelaxes) {
  BenchSummaryBuilder builder(PointTarget(StokesVector(0.0, 0.6, 0.8)));
  for (int period = 1; period <= 3; ++period) {
    for (uint64_t i = 1; i <= 10000; ++i) builder.OnSample(Sample(i, static_cast<double>(i) * 0.008));
    const BenchSummary s = builder.Take(period * 50'000'000, period);
    EXPECT_LE(s.trail.size(), kMaxSummaryTrailPoints);
    EXPECT_GE(s.trail.size(), kMaxSummaryTrailPoints / 2);
    EXPECT_NEAR(s.trail.front()[3], std::sin(0.008 * std::numbers::pi / 180.0), 1e-12);  // the first sample
    EXPECT_GT(s.trail.back()[3], std::sin(60.0 * std::numbers::pi / 180.0));            // and near the end
  }
  // A slow bench afterwards: every sample is in the trail again once the stride relaxed.
  for (int period = 0; period < 12; ++period) {
    for (uint64_t i = 1; i <= 5; ++i) builder.OnSample(Sample(i, 1.0));
    builder.Take(1'000'000'000 + period * 50'000'000, 0);
  }
  for (uint64_t i = 1; i <= 5; ++i) builder.OnSample(Sample(i, 1.0));
  EXPECT_EQ(builder.Take(2'000'000'000, 0).trail.size(), 5u);
}

TEST(BenchSummaryBuilderTest, LoopLatencyOfEachNewlyAnsweredSampleAndTheLatestState) {
  BenchSummaryBuilder builder(PointTarget(StokesVector(0.0, 0.6, 0.8)));
  for (uint64_t i = 1; i <= 100; ++i) {
    const int64_t published = 1'000'000'000 + static_cast<int64_t>(i) * 1'000'000;
    builder.OnState(State(i, published), published + static_cast<int64_t>(i) * 1000);
    builder.OnState(State(i, published), published + 999'000'000);  // a heartbeat: not counted again
  }
  BenchSummary s = builder.Take(1, 1);
  EXPECT_EQ(s.latencies, 100u);
  EXPECT_DOUBLE_EQ(s.latency_p50_us, 50.0);
  EXPECT_DOUBLE_EQ(s.latency_p99_us, 99.0);
  EXPECT_DOUBLE_EQ(s.latency_max_us, 100.0);
  ASSERT_TRUE(s.state);
  EXPECT_EQ(s.state->answers_sample, 100u);
  EXPECT_EQ(builder.Take(2, 2).latencies, 0u);  // a new period
}

}  // namespace
}  // namespace dpc
