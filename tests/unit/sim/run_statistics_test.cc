#include "dpc/sim/run_statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "support/run_summary_expect.h"

namespace dpc {
namespace {

constexpr double kDeg = M_PI / 180.0;

const Target kTarget = Target::Point(StokesVector(0, 0.6, 0.8));

ControlVector Phi(double a, double b) {
  ControlVector v(2);
  v << a, b;
  return v;
}

// A unit S_out at `error_rad` from the target point.
StokesVector At(double error_rad) {
  const Vector3 p = kTarget.point(), q(1, 0, 0);  // q ⊥ p
  return std::cos(error_rad) * p + std::sin(error_rad) * q;
}

// A unit S_out whose polarizer leak is `leak` (= sin²(α/2)).
StokesVector WithLeak(double leak) { return At(2.0 * std::asin(std::sqrt(leak))); }

TEST(RunStatisticsTest, LockTimeIsTheStartOfTheFinalStretchBelowThreshold) {
  RunStatistics stats(kTarget, 2, 1.0, 10.0, std::nullopt);
  const double errors_deg[] = {50, 20, 5, 4, 30, 3, 2, 1};  // below at 2, above at 4, below from 5
  for (int k = 0; k < 8; ++k) {
    stats.AddSample(1.0 + 0.1 * k, At(errors_deg[k] * kDeg), Phi(0, 0));
  }
  const RunSummary s = stats.Summarize(8, 0);
  ASSERT_TRUE(s.lock_time_s.has_value());
  EXPECT_NEAR(*s.lock_time_s, 0.5, 1e-12);
  ASSERT_TRUE(s.first_lock_time_s.has_value());
  EXPECT_NEAR(*s.first_lock_time_s, 0.2, 1e-12);
  EXPECT_EQ(s.excursions, 1);
  // Statistics from the first lock: 5, 4, 30, 3, 2, 1.
  EXPECT_EQ(s.statistics_samples, 6);
  EXPECT_NEAR(s.statistics_start_s, 1.2, 1e-12);
  EXPECT_NEAR(s.error_deg.mean, 45.0 / 6.0, 1e-9);
  EXPECT_NEAR(s.error_deg.p50, 3.5, 1.5);
  EXPECT_NEAR(s.error_deg.max, 30.0, 1e-9);
}

TEST(RunStatisticsTest, ExcursionsAreCountedWithHysteresisAndCrossingsBesideThem) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, std::nullopt);
  // Locked (3° < 5°: armed), then hovering about the threshold: three crossings, one excursion;
  // below half the threshold again (4°), then up: a second excursion.
  const double errors_deg[] = {50, 3, 11, 9, 11, 9, 11, 9, 6, 12, 4, 12, 2};
  const int n = static_cast<int>(std::size(errors_deg));
  for (int k = 0; k < n; ++k) stats.AddSample(0.1 * k, At(errors_deg[k] * kDeg), Phi(0, 0));
  const RunSummary s = stats.Summarize(n, 0);
  EXPECT_EQ(s.threshold_crossings, 5);
  EXPECT_EQ(s.excursions, 2);
  ASSERT_TRUE(s.first_lock_time_s.has_value());
  EXPECT_NEAR(*s.first_lock_time_s, 0.1, 1e-12);
  ASSERT_TRUE(s.lock_time_s.has_value());  // the last relock, not the first lock
  EXPECT_NEAR(*s.lock_time_s, 1.2, 1e-12);
  // The window: from the first lock to the last sample.
  EXPECT_NEAR(s.statistics_start_s, 0.1, 1e-12);
  EXPECT_NEAR(s.statistics_end_s, 1.2, 1e-12);
  EXPECT_EQ(s.statistics_samples, n - 1);
}

TEST(RunStatisticsTest, SettlingTimeLeavesTheLockInTransientOut) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, std::nullopt, 0.25);
  const double errors_deg[] = {50, 9, 6, 3, 1, 1, 1};  // first lock at t = 0.1
  for (int k = 0; k < 7; ++k) stats.AddSample(0.1 * k, At(errors_deg[k] * kDeg), Phi(0, 0));
  const RunSummary s = stats.Summarize(7, 0);
  EXPECT_NEAR(s.statistics_start_s, 0.4, 1e-12);  // 0.1 + 0.25, on the next sample
  EXPECT_EQ(s.statistics_samples, 3);
  EXPECT_NEAR(s.error_deg.max, 1.0, 1e-9);
  EXPECT_NEAR(*s.first_lock_time_s, 0.1, 1e-12);
}

TEST(RunStatisticsTest, NoLockWhenTheRunEndsAboveThreshold) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, std::nullopt);
  stats.AddSample(0.0, At(5 * kDeg), Phi(0, 0));
  stats.AddSample(0.1, At(50 * kDeg), Phi(0, 0));
  const RunSummary s = stats.Summarize(2, 0);
  EXPECT_FALSE(s.lock_time_s.has_value());
  EXPECT_TRUE(s.first_lock_time_s.has_value());
}

TEST(RunStatisticsTest, RecoveryStretchesAreTheTimesAtOrAboveFortyDecibels) {
  // From 0.1 s: 0.5° (below 40 dB), then 2° for 0.3 s (a transient), below, 1.5° for 0.1 s, and
  // 3° from 1.0 s to the end (0.2 s): three stretches, the longest the first (0.3 s from 0.2 s).
  RunStatistics stats(kTarget, 2, 0.0, 10.0, 0.1);
  const double errors_deg[] = {0.5, 0.5, 2, 2, 2, 0.5, 1.5, 0.5, 0.5, 0.5, 3, 3, 3};
  for (int k = 0; k < 13; ++k) stats.AddSample(0.1 * k, At(errors_deg[k] * kDeg), Phi(0, 0));
  const RunSummary r = stats.Summarize(13, 0);
  EXPECT_NEAR(RunStatistics::kRecoveryThresholdDeg, 1.1459, 1e-4);
  EXPECT_EQ(r.recovery_stretches, 3);
  EXPECT_NEAR(r.longest_recovery_s, 0.3, 1e-12);
  EXPECT_NEAR(r.longest_recovery_from_s, 0.2, 1e-12);

  // The last stretch runs to the window's end: the longest when nothing before is as long.
  RunStatistics tail(kTarget, 2, 0.0, 10.0, 0.0);
  const double tail_deg[] = {0.5, 1.5, 0.5, 0.5, 2, 2, 2, 2};
  for (int k = 0; k < 8; ++k) tail.AddSample(0.1 * k, At(tail_deg[k] * kDeg), Phi(0, 0));
  const RunSummary t = tail.Summarize(8, 0);
  EXPECT_EQ(t.recovery_stretches, 2);
  EXPECT_NEAR(t.longest_recovery_s, 0.3, 1e-12);
  EXPECT_NEAR(t.longest_recovery_from_s, 0.4, 1e-12);

  // Never above: none, and no start.
  RunStatistics calm(kTarget, 2, 0.0, 10.0, 0.0);
  for (int k = 0; k < 5; ++k) calm.AddSample(0.1 * k, At(1.0 * kDeg), Phi(0, 0));
  const RunSummary c = calm.Summarize(5, 0);
  EXPECT_EQ(c.recovery_stretches, 0);
  EXPECT_EQ(c.longest_recovery_s, 0.0);
  EXPECT_TRUE(std::isnan(c.longest_recovery_from_s));
}

TEST(RunStatisticsTest, NeverLockedMeansNoErrorStatistics) {
  RunStatistics stats(kTarget, 2, 0.0, 1.0, std::nullopt);
  stats.AddSample(0.0, At(5 * kDeg), Phi(0, 0));
  const RunSummary s = stats.Summarize(1, 0);
  EXPECT_FALSE(s.first_lock_time_s.has_value());
  EXPECT_EQ(s.statistics_samples, 0);
  EXPECT_TRUE(std::isnan(s.error_deg.mean));
}

TEST(RunStatisticsTest, FixedWindowStartAndExtinctionMeans) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, 0.15);
  stats.AddSample(0.1, WithLeak(0.5), Phi(0, 0));   // before the window
  stats.AddSample(0.2, WithLeak(1e-2), Phi(0, 0));  // −20 dB
  stats.AddSample(0.3, WithLeak(1e-4), Phi(0, 0));  // −40 dB
  const RunSummary s = stats.Summarize(3, 0);
  EXPECT_EQ(s.statistics_samples, 2);
  EXPECT_NEAR(s.extinction_db_mean, -30.0, 1e-9);
  EXPECT_NEAR(s.extinction_db_power_mean, 10 * std::log10(0.5 * (1e-2 + 1e-4)), 1e-9);
}

TEST(RunStatisticsTest, PerfectAlignmentIsFlooredNotMinusInfinity) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, 0.0);
  stats.AddSample(0.0, kTarget.point(), Phi(0, 0));
  EXPECT_NEAR(stats.Summarize(1, 0).extinction_db_mean, -200.0, 1e-9);
}

TEST(RunStatisticsTest, ControlExtremesAndPercentiles) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, std::nullopt);
  for (int k = 0; k <= 1000; ++k) {
    stats.AddSample(k * 1e-3, At(1 * kDeg), Phi(-1.0 + 0.002 * k, 3.0));
  }
  const RunSummary s = stats.Summarize(1001, 0);
  EXPECT_NEAR(s.phi_min[0], -1.0, 1e-12);
  EXPECT_NEAR(s.phi_max[0], 1.0, 1e-12);
  EXPECT_NEAR(s.phi_p1[0], -0.98, 0.01);
  EXPECT_NEAR(s.phi_p99[0], 0.98, 0.01);
  EXPECT_NEAR(s.phi_p1[1], 3.0, 1e-9);
}

TEST(RunStatisticsTest, BatchBoundariesDoNotChangeTheResult) {
  // More samples than one batch, with a lock in the middle of the second batch.
  RunStatistics batched(kTarget, 2, 0.0, 10.0, std::nullopt);
  const int n = 3 * RunStatistics::kBatch + 17;
  double sum_deg = 0.0;
  int counted = 0;
  for (int k = 0; k < n; ++k) {
    const double error_deg = k < RunStatistics::kBatch + 100 ? 30.0 : 1.0 + 0.001 * k;
    batched.AddSample(k * 1e-6, At(error_deg * kDeg), Phi(0.001 * k, -0.002 * k));
    if (k >= RunStatistics::kBatch + 100) {
      sum_deg += error_deg;
      ++counted;
    }
  }
  const RunSummary s = batched.Summarize(n, 0);
  ASSERT_TRUE(s.first_lock_time_s.has_value());
  EXPECT_NEAR(*s.first_lock_time_s, (RunStatistics::kBatch + 100) * 1e-6, 1e-12);
  EXPECT_EQ(s.statistics_samples, counted);
  EXPECT_NEAR(s.error_deg.mean, sum_deg / counted, 1e-9);
  EXPECT_NEAR(s.phi_max[0], 0.001 * (n - 1), 1e-12);
  EXPECT_NEAR(s.phi_min[1], -0.002 * (n - 1), 1e-12);
}

// A long locked run whose batches are mostly quiet (every sample below the threshold: Flush's
// steady path) with excursions, crossings without rearming, and a relock between them, against a
// sample-by-sample reference of the rules in the header comment.
TEST(RunStatisticsTest, QuietBatchesAndEventfulOnesFollowTheSameRules) {
  constexpr double kThresholdDeg = 10.0;
  RunStatistics stats(kTarget, 2, 0.0, kThresholdDeg, std::nullopt);
  const int n = 12 * RunStatistics::kBatch + 5;
  const auto error_deg_at = [](int k) {
    if (k < 40) return 30.0;                       // before the first lock
    const int in_batch = k % RunStatistics::kBatch, batch = k / RunStatistics::kBatch;
    if (batch == 3 && in_batch >= 100 && in_batch < 120) return 12.0;  // an excursion
    if (batch == 5 && in_batch >= 10 && in_batch < 20) return 11.0;    // an excursion, then
    if (batch == 5 && in_batch >= 20 && in_batch < 60) return 7.0;     // not below half again:
    if (batch == 5 && in_batch >= 60 && in_batch < 62) return 11.0;    // a crossing only
    if (batch == 6 && in_batch >= 200 && in_batch < 210) return 12.0;  // an excursion; the
    if (batch == 6 && in_batch >= 210) return 7.0;  // rearming comes with the quiet batch 7
    if (batch == 8 && in_batch < 5) return 12.0;     // an excursion only if batch 7 rearmed
    if (batch == 8 && in_batch >= 200) return 20.0;  // an excursion across a batch boundary
    if (batch == 9 && in_batch < 30) return 20.0;
    return 2.0 + 0.5 * std::sin(0.01 * k);         // locked, below half the threshold
  };
  // The reference.
  bool below = false, armed = false;
  std::optional<int> first_lock;
  int below_since = -1, excursions = 0, crossings = 0, window = 0;
  double sum_deg = 0.0;
  for (int k = 0; k < n; ++k) {
    const double e = error_deg_at(k);
    stats.AddSample(k * 1e-6, At(e * kDeg), Phi(0.001 * k, 0.0));
    const bool now_below = e < kThresholdDeg;
    if (now_below && !below) {
      below_since = k;
      if (!first_lock) first_lock = k;
    } else if (!now_below && below) {
      ++crossings;
      if (armed) ++excursions, armed = false;
    }
    if (e < 0.5 * kThresholdDeg) armed = true;
    below = now_below;
    if (first_lock) ++window, sum_deg += e;
  }
  const RunSummary s = stats.Summarize(n, 0);
  EXPECT_EQ(s.excursions, excursions);
  EXPECT_EQ(excursions, 5);
  EXPECT_EQ(s.threshold_crossings, crossings);
  EXPECT_EQ(crossings, 6);
  ASSERT_TRUE(s.first_lock_time_s.has_value());
  EXPECT_NEAR(*s.first_lock_time_s, *first_lock * 1e-6, 1e-15);
  ASSERT_TRUE(s.lock_time_s.has_value());
  EXPECT_NEAR(*s.lock_time_s, below_since * 1e-6, 1e-15);
  EXPECT_EQ(s.statistics_samples, window);
  EXPECT_NEAR(s.statistics_end_s, (n - 1) * 1e-6, 1e-15);
  EXPECT_NEAR(s.error_deg.mean, sum_deg / window, 1e-9);
  EXPECT_NEAR(s.error_deg.max, 20.0, 1e-9);  // the 30° before the first lock are outside
}

TEST(RunStatisticsTest, UpdateCounters) {
  RunStatistics stats(kTarget, 2, 0.0, 10.0, std::nullopt);
  stats.AddUpdate(true, false, false, false, SingularValues::Exact(1.0, 0.5));
  stats.AddUpdate(false, true, false, false, SingularValues::FromGram(0.01));
  // G = diag(4, 1e-4): σ = 2 and 0.01, below 0.1·σ_max.
  stats.AddUpdate(true, false, true, true, SingularValues::FromGram(4.0, 1e-4, 0.0, 4e-4));
  const RunSummary s = stats.Summarize(3, 7);
  EXPECT_EQ(s.updates, 3);
  EXPECT_NEAR(s.nullspace_active_fraction, 2.0 / 3.0, 1e-15);
  EXPECT_EQ(s.failed_updates, 1);
  EXPECT_EQ(s.rank_deficient_updates, 1);
  EXPECT_EQ(s.clamped_updates, 1);
  EXPECT_EQ(s.resets, 7);
  EXPECT_NEAR(s.sigma_min_min, 0.01, 1e-15);
  EXPECT_NEAR(s.near_singular_fraction, 1.0 / 3.0, 1e-15);
}

// The batched simulator's way in: samples strided among other runs' (AddSamples), their controls
// four runs at once (AddControls), the updates tallied apart (AddUpdates). Every figure must be
// the sample-by-sample one, bit for bit, whatever the chunks (across the buffer's batches too)
// and when the ways are mixed.
TEST(RunStatisticsTest, StridedSamplesControlsAndTalliesEqualOneAtATime) {
  constexpr int kRuns = 3, kStride = 8, kControls = 4;
  const int n = 3 * RunStatistics::kBatch + 41;
  const double period_s = 2e-8;
  std::vector<double> out[3], phi[kControls];
  for (auto& v : out) v.assign(static_cast<size_t>(n) * kStride, NAN);
  for (auto& v : phi) v.assign(static_cast<size_t>(n) * kStride, NAN);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < kRuns; ++j) {
      // An error that locks, leaves and comes back; a different one in each run.
      const double error_deg = k < 300 + 40 * j ? 20.0 - 0.05 * k : 0.2 + 3.0 * (k % 97 == j);
      const StokesVector s = At(error_deg * kDeg);
      const size_t at = static_cast<size_t>(k) * kStride + static_cast<size_t>(j);
      for (int c = 0; c < 3; ++c) out[c][at] = s[c];
      for (int c = 0; c < kControls; ++c) phi[c][at] = std::sin(0.01 * k + c + j) * (c + 1);
    }
  }
  std::vector<RunStatistics> alone, strided;
  for (int j = 0; j < kRuns; ++j) {
    alone.emplace_back(kTarget, kControls, 0.0, 1.0, std::nullopt);
    strided.emplace_back(kTarget, kControls, 0.0, 1.0, std::nullopt);
  }
  UpdateTally tallies[kRuns];
  const int chunks[] = {1, 63, 64, 200, 7, 256, 300};
  int k = 0;
  for (int chunk = 0; k < n; ++chunk) {
    const int count = std::min(chunks[chunk % 7], n - k);
    for (int j = 0; j < kRuns; ++j) {
      for (int i = k; i < k + count; ++i) {
        const size_t at = static_cast<size_t>(i) * kStride + static_cast<size_t>(j);
        const double controls[kControls] = {phi[0][at], phi[1][at], phi[2][at], phi[3][at]};
        alone[static_cast<size_t>(j)].AddSample(static_cast<double>(i) * period_s,
                                                StokesVector(out[0][at], out[1][at], out[2][at]),
                                                controls);
        const SingularValues sv = SingularValues::FromGram(1.0 + i % 5, 0.5, 0.1 * j, 0.4 + i % 3);
        alone[static_cast<size_t>(j)].AddUpdate(i % 3 == 0, i % 11 == 0, false, false, sv);
        tallies[j].Add(i % 3 == 0, i % 11 == 0, false, false, sv);
      }
      RunStatistics& run = strided[static_cast<size_t>(j)];
      if (chunk % 5 == 4) {  // this chunk one at a time: the ways mixed
        for (int i = k; i < k + count; ++i) {
          const size_t at = static_cast<size_t>(i) * kStride + static_cast<size_t>(j);
          const double controls[kControls] = {phi[0][at], phi[1][at], phi[2][at], phi[3][at]};
          run.AddSample(static_cast<double>(i) * period_s,
                        StokesVector(out[0][at], out[1][at], out[2][at]), controls);
        }
        continue;
      }
      const size_t at = static_cast<size_t>(k) * kStride + static_cast<size_t>(j);
      const double* s_out[3] = {&out[0][at], &out[1][at], &out[2][at]};
      run.AddSamples(k, period_s, count, s_out, kStride);
    }
    if (chunk % 5 != 4) {
      RunStatistics* runs[4] = {&strided[0], &strided[1], &strided[2]};
      const size_t at = static_cast<size_t>(k) * kStride;
      const double* controls[kControls] = {&phi[0][at], &phi[1][at], &phi[2][at], &phi[3][at]};
      RunStatistics::AddControls(runs, kRuns, controls, count, kStride);
    }
    k += count;
  }
  for (int j = 0; j < kRuns; ++j) {
    strided[static_cast<size_t>(j)].AddUpdates(tallies[j]);
    const RunSummary a = alone[static_cast<size_t>(j)].Summarize(n, 0);
    const RunSummary b = strided[static_cast<size_t>(j)].Summarize(n, 0);
    SCOPED_TRACE(j);
    ASSERT_TRUE(a.first_lock_time_s.has_value());
    EXPECT_GT(a.excursions, 0);
    ExpectSameRunSummary(a, b);
  }
}

}  // namespace
}  // namespace dpc
