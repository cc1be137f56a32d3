#pragma once
// Streaming statistics of a closed-loop run, in O(1) memory whatever its length: fixed-size
// logarithmic histograms (log_histogram.h) for percentiles, compensated sums for means.
//
//   error        angular distance of the true S_out to the target, degrees; over the
//                statistics window (from the first lock after activation, or a given start)
//   extinction   leak through a polarizer aligned with the (nearest) target point,
//                L = sin²(α/2) = (1 − S_out·S*)/2 for a point target:
//                  extinction_db_mean        mean over samples of 10·log10(L) (L floored at 1e-20)
//                  extinction_db_power_mean  10·log10(mean L): what a power meter would read
//   lock         "locked" from the start of the last stretch that stays below the lock threshold
//                until the end of the run; lock_time_s counts from activation (unset if the
//                last sample is above the threshold). first_lock_time_s: the first time below.
//                excursions: upward crossings of the threshold after the first lock.
//   controls     min, max, 1st and 99th percentiles of each applied φ_i, from activation on
//   controller   fraction of updates with the null-space term active, failed and clamped
//                updates, the smallest σ_min of the task Jacobian

#include <cstdint>
#include <optional>
#include <vector>

#include "dpc/optics/stokes.h"
#include "dpc/sim/log_histogram.h"

namespace dpc {

struct ErrorSummary {
  double mean = 0.0, p50 = 0.0, p99 = 0.0, max = 0.0;
};

struct RunSummary {
  int64_t samples = 0;              ///< simulated samples
  int64_t statistics_samples = 0;   ///< samples in the error statistics window
  double statistics_start_s = 0.0;  ///< start of that window (NaN if empty)
  ErrorSummary error_deg;
  double extinction_db_mean = 0.0;
  double extinction_db_power_mean = 0.0;
  std::optional<double> lock_time_s;
  std::optional<double> first_lock_time_s;
  int64_t excursions = 0;
  std::vector<double> phi_min, phi_max, phi_p1, phi_p99;
  int64_t updates = 0;  ///< controller updates (samples from activation on)
  double nullspace_active_fraction = 0.0;
  int64_t failed_updates = 0;         ///< singular or non-finite: not applied
  int64_t rank_deficient_updates = 0; ///< applied, from a rank-deficient task
  int64_t clamped_updates = 0;        ///< clamped into a control range
  int64_t resets = 0;
  double sigma_min_min = 0.0;         ///< smallest σ_min of the task Jacobian seen
  double sigma_min_p1 = 0.0;
};

class RunStatistics {
 public:
  /// `statistics_start_s`: fixed window start, or nullopt for "from the first lock".
  RunStatistics(int control_count, double activation_s, double lock_threshold_deg,
                std::optional<double> statistics_start_s);

  /// Real-time. One sample at time t_s after activation: the true error angle (radians), the
  /// polarizer leak, and the applied controls.
  void AddSample(double t_s, double error_rad, double leak, const ControlVector& phi_applied);

  /// Real-time. One controller update's outcome.
  void AddUpdate(bool nullspace_active, bool failed, bool rank_deficient, bool clamped,
                 double sigma_min);

  /// The summary so far; `samples` is the total simulated sample count, `resets` the law's.
  RunSummary Summarize(int64_t samples, int64_t resets) const;

 private:
  double activation_s_;
  double lock_threshold_rad_;
  std::optional<double> fixed_start_s_;

  // Error window.
  bool window_open_ = false;
  double window_start_s_ = NAN;
  LogHistogram error_deg_;
  double leak_db_sum_ = 0.0, leak_db_compensation_ = 0.0;
  double leak_sum_ = 0.0, leak_compensation_ = 0.0;

  // Lock tracking.
  bool below_ = false;
  double below_since_s_ = NAN;
  std::optional<double> first_lock_s_;
  int64_t excursions_ = 0;

  // Controls and controller.
  std::vector<LogHistogram> phi_;
  int64_t updates_ = 0, nullspace_active_ = 0, failed_ = 0, rank_deficient_ = 0, clamped_ = 0;
  LogHistogram sigma_min_;
};

}  // namespace dpc
