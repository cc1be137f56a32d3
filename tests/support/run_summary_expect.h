#pragma once
// Test support: two run summaries compared field by field, bit for bit (a batch's lane against
// its run alone, a statistics fed one way against another).

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "dpc/sim/run_statistics.h"

namespace dpc {

// Bit for bit (NaN equals NaN).
#define EXPECT_SAME_BITS(a, b) \
  EXPECT_EQ(std::bit_cast<uint64_t>(static_cast<double>(a)), std::bit_cast<uint64_t>(static_cast<double>(b))) \
      << #a << " = " << (a) << " vs " << (b)

/// Every field of two run summaries, bit for bit (NaN equals NaN).
inline void ExpectSameRunSummary(const RunSummary& x, const RunSummary& y) {
  EXPECT_EQ(x.samples, y.samples);
  EXPECT_EQ(x.statistics_samples, y.statistics_samples);
  EXPECT_SAME_BITS(x.statistics_start_s, y.statistics_start_s);
  EXPECT_SAME_BITS(x.statistics_end_s, y.statistics_end_s);
  EXPECT_SAME_BITS(x.error_deg.mean, y.error_deg.mean);
  EXPECT_SAME_BITS(x.error_deg.p50, y.error_deg.p50);
  EXPECT_SAME_BITS(x.error_deg.p99, y.error_deg.p99);
  EXPECT_SAME_BITS(x.error_deg.max, y.error_deg.max);
  EXPECT_SAME_BITS(x.extinction_db_mean, y.extinction_db_mean);
  EXPECT_SAME_BITS(x.extinction_db_power_mean, y.extinction_db_power_mean);
  EXPECT_EQ(x.lock_time_s, y.lock_time_s);
  EXPECT_EQ(x.first_lock_time_s, y.first_lock_time_s);
  EXPECT_EQ(x.excursions, y.excursions);
  EXPECT_EQ(x.threshold_crossings, y.threshold_crossings);
  EXPECT_EQ(x.recovery_stretches, y.recovery_stretches);
  EXPECT_SAME_BITS(x.longest_recovery_s, y.longest_recovery_s);
  EXPECT_SAME_BITS(x.longest_recovery_from_s, y.longest_recovery_from_s);
  ASSERT_EQ(x.phi_min.size(), y.phi_min.size());
  for (size_t e = 0; e < x.phi_min.size(); ++e) {
    EXPECT_SAME_BITS(x.phi_min[e], y.phi_min[e]);
    EXPECT_SAME_BITS(x.phi_max[e], y.phi_max[e]);
    EXPECT_SAME_BITS(x.phi_p1[e], y.phi_p1[e]);
    EXPECT_SAME_BITS(x.phi_p99[e], y.phi_p99[e]);
  }
  EXPECT_EQ(x.updates, y.updates);
  EXPECT_SAME_BITS(x.nullspace_active_fraction, y.nullspace_active_fraction);
  EXPECT_EQ(x.failed_updates, y.failed_updates);
  EXPECT_EQ(x.rank_deficient_updates, y.rank_deficient_updates);
  EXPECT_EQ(x.clamped_updates, y.clamped_updates);
  EXPECT_SAME_BITS(x.sigma_min_min, y.sigma_min_min);
  EXPECT_SAME_BITS(x.near_singular_fraction, y.near_singular_fraction);
}

}  // namespace dpc
