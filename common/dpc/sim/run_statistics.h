#pragma once
// Streaming statistics of a closed-loop run, in O(1) memory whatever its length: fixed-size
// logarithmic histograms (log_histogram.h) for percentiles, compensated sums for means.
//
//   error        angular distance of the true S_out to the target, degrees; over the
//                statistics window (from a settling time after the first lock after
//                activation, or from a given start)
//   extinction   leak through a polarizer aligned with the (nearest) target point,
//                L = sin²(α/2) = (1 − S_out·S*)/2 for a point target:
//                  extinction_db_mean        mean over samples of 10·log10(L) (L floored at 1e-20;
//                                            Σ ln L through LogSumAccumulator, no log per sample)
//                  extinction_db_power_mean  10·log10(mean L): what a power meter would read
//   lock         first_lock_time_s: the first time below the lock threshold (from activation).
//                excursions: rises above the threshold counted with hysteresis, as other
//                implementations count them: a new excursion only after the error fell below
//                half the threshold (a noisy error hovering at the threshold is one excursion,
//                not hundreds); threshold_crossings: every upward crossing after the first lock.
//                lock_time_s: the start of the last stretch that stays below the threshold until
//                the end of the run (unset if the last sample is above it): on a long run with
//                excursions that is the last relock, not the first lock.
//   recovery     stretches of the statistics window with the error at or above the 40-dB
//                threshold (leak 1e-4 through the polarizer: 2·asin(0.01) = 1.146°): how many, and
//                the longest (from its first sample above to the first back below, or to the
//                window's end): after a transient (a lightning stroke) the time back below 40 dB.
//   controls     min, max, 1st and 99th percentiles of each applied φ_i, from activation on
//   controller   fraction of updates with the null-space term active, failed and clamped
//                updates, the smallest σ_min of the task Jacobian and the fraction of updates
//                with σ_min < 0.1·σ_max (near a singularity)

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "dpc/control/singular_values.h"
#include "dpc/optics/count_dispatch.h"
#include "dpc/control/target.h"
#include "dpc/optics/stokes.h"
#include "dpc/sim/log_histogram.h"
#include "dpc/sim/log_sum_accumulator.h"

namespace dpc {

struct ErrorSummary {
  double mean = 0.0, p50 = 0.0, p99 = 0.0, max = 0.0;
};

struct RunSummary {
  int64_t samples = 0;              ///< simulated samples
  int64_t statistics_samples = 0;   ///< samples in the error statistics window
  double statistics_start_s = 0.0;  ///< start of that window (NaN if empty)
  double statistics_end_s = 0.0;    ///< its last sample's time (NaN if empty)
  ErrorSummary error_deg;
  double extinction_db_mean = 0.0;
  double extinction_db_power_mean = 0.0;
  std::optional<double> lock_time_s;
  std::optional<double> first_lock_time_s;
  int64_t excursions = 0;           ///< with hysteresis (see above)
  int64_t threshold_crossings = 0;  ///< every upward crossing after the first lock
  int64_t recovery_stretches = 0;        ///< stretches at or above kRecoveryThresholdDeg
  double longest_recovery_s = 0.0;       ///< the longest of them (0 if none)
  double longest_recovery_from_s = NAN;  ///< its first sample's time (NaN if none)
  std::vector<double> phi_min, phi_max, phi_p1, phi_p99;
  int64_t updates = 0;  ///< controller updates (samples from activation on)
  double nullspace_active_fraction = 0.0;
  int64_t failed_updates = 0;         ///< singular or non-finite: not applied
  int64_t rank_deficient_updates = 0; ///< applied, from a rank-deficient task
  int64_t clamped_updates = 0;        ///< clamped into a control range
  int64_t resets = 0;
  double sigma_min_min = 0.0;         ///< smallest σ_min of the task Jacobian seen
  /// Fraction of updates near a singularity: σ_min < kNearSingularRatio·σ_max.
  double near_singular_fraction = 0.0;
};

/// What the statistics keep of the controller's updates (RunStatistics::AddUpdate). A batched
/// simulator tallies its lanes' updates apart and adds each lane's at once (AddUpdates).
struct UpdateTally {
  /// σ_min below this fraction of σ_max counts as near a singularity.
  static constexpr double kNearSingularRatio = 0.1;

  int64_t updates = 0, nullspace_active = 0, failed = 0, rank_deficient = 0, clamped = 0;
  int64_t near_singular = 0;           ///< updates with σ_min < kNearSingularRatio·σ_max
  double min_sigma_squared = INFINITY;  ///< the smallest σ_min² seen

  /// Another tally's updates, as if each had been added here.
  void Merge(const UpdateTally& other) {
    updates += other.updates;
    nullspace_active += other.nullspace_active;
    failed += other.failed;
    rank_deficient += other.rank_deficient;
    clamped += other.clamped;
    near_singular += other.near_singular;
    min_sigma_squared = std::min(min_sigma_squared, other.min_sigma_squared);
  }
  /// One update's outcome. The singular values' square roots are taken only for a candidate
  /// new minimum.
  void Add(bool nullspace_active_now, bool failed_now, bool rank_deficient_now, bool clamped_now,
           const SingularValues& singular_values) {
    ++updates;
    nullspace_active += nullspace_active_now;
    failed += failed_now;
    rank_deficient += rank_deficient_now;
    clamped += clamped_now;
    AddSingularValues(singular_values);
  }
  /// The singular values' part of Add: the smallest σ_min² and the near-singular count.
  void AddSingularValues(const SingularValues& singular_values) {
    if (singular_values.MayBeBelow(min_sigma_squared)) {
      min_sigma_squared = std::min(min_sigma_squared, singular_values.min_squared());
    }
    near_singular += singular_values.IsBelowRatio(kNearSingularRatio);
  }
};

class RunStatistics {
 public:
  /// The error of a 40-dB leak (sin²(α/2) = 1e-4): the recovery statistics' threshold.
  static constexpr double kRecoveryThresholdRad = 0.020000333348334228;  // 2·asin(0.01)
  static constexpr double kRecoveryThresholdDeg = kRecoveryThresholdRad * 180.0 / M_PI;

  /// Samples are buffered and folded into the statistics this many at a time: independent
  /// square roots, arcsines and logarithms then overlap in the pipeline instead of lengthening
  /// each sample's dependency chain.
  static constexpr int kBatch = 256;

  /// `statistics_start_s`: fixed window start, or nullopt for "settle_s after the first lock".
  /// Keeps a reference to `target`.
  RunStatistics(const Target& target, int control_count, double activation_s,
                double lock_threshold_deg, std::optional<double> statistics_start_s,
                double settle_s = 0.0);

  /// Real-time. One sample at time t_s from activation on: the true S_out and the applied
  /// controls. Samples must come in time order.
  void AddSample(double t_s, const StokesVector& s_out, const ControlVector& phi_applied) {
    AddSample(t_s, s_out, phi_applied.data());
  }
  /// The same with the controls as control_count consecutive values.
  void AddSample(double t_s, const StokesVector& s_out, const double* phi_applied);
  /// Real-time. `count` samples, the i-th at t_s = (first_sample + i)·sample_period_s with the
  /// true S_out (s_out[c][i·stride], c < 3), without their controls: together with AddControls
  /// the same as AddSample on each, for a caller holding them strided (the batched simulator's
  /// lanes).
  void AddSamples(int64_t first_sample, double sample_period_s, int count,
                  const double* const* s_out, std::ptrdiff_t stride);
  /// Real-time. The controls of `count` samples of up to eight runs at once (the lanes of a
  /// batch), run j's (statistics[j], j < runs ≤ 8, each with control_count ≤ 4) being
  /// phi[c][i·row_stride + j] (row_stride ≥ 4, and ≥ 8 for more than four runs): what
  /// AddSample gives the control statistics.
  static void AddControls(RunStatistics* const* statistics, int runs, const double* const* phi,
                          int count, std::ptrdiff_t row_stride);

  /// σ_min below this fraction of σ_max counts as near a singularity.
  static constexpr double kNearSingularRatio = UpdateTally::kNearSingularRatio;

  /// Real-time. One controller update's outcome (UpdateTally::Add).
  void AddUpdate(bool nullspace_active, bool failed, bool rank_deficient, bool clamped,
                 const SingularValues& singular_values) {
    updates_.Add(nullspace_active, failed, rank_deficient, clamped, singular_values);
  }
  /// Updates tallied elsewhere: the same as AddUpdate on each of them.
  void AddUpdates(const UpdateTally& tally) { updates_.Merge(tally); }

  /// The summary so far; `samples` is the total simulated sample count, `resets` the law's.
  RunSummary Summarize(int64_t samples, int64_t resets) const;

 private:
  /// Buffers sample i's output: |S_out − S*|² for a point target, S_out itself otherwise.
  void PendOutput(int i, double x, double y, double z) {
    if (point_target_) {
      const double dx = x - target_x_, dy = y - target_y_, dz = z - target_z_;
      pending_chord_squared_[i] = dx * dx + dy * dy + dz * dz;
    } else {
      pending_s_out_[i][0] = x;
      pending_s_out_[i][1] = y;
      pending_s_out_[i][2] = z;
    }
  }
  /// Folds the buffered samples into the statistics.
  void Flush() const;
  /// The recovery stretches through `count` window samples (error in degrees, time).
  void TrackRecovery(const double* error_deg, const double* t_s, int count) const;

  const Target& target_;
  bool point_target_;
  double target_x_, target_y_, target_z_;
  int control_count_;
  double activation_s_;
  double lock_threshold_rad_;
  std::optional<double> fixed_start_s_;
  double settle_s_;

  // Buffered samples (mutable: Summarize flushes them).
  mutable int pending_ = 0;
  mutable double pending_t_s_[kBatch];
  mutable double pending_s_out_[kBatch][3];        ///< set targets
  mutable double pending_chord_squared_[kBatch];   ///< point targets: |S_out − S*|²
  /// kBatch rows of phi_stride_ (sample-major): up to four controls fill one row of four, which
  /// Flush adds to the four histograms at once (LogHistogram::AddBatchLanes).
  mutable std::vector<double> pending_phi_;
  mutable int pending_phi_rows_ = 0;  ///< AddSample's (AddSamples leaves the controls out)
  int phi_stride_;

  // Error window.
  mutable bool window_open_ = false;
  mutable double window_start_s_ = NAN;
  mutable double window_end_s_ = NAN;
  mutable LogHistogram error_deg_;
  mutable LogSumAccumulator leak_log_sum_;  ///< Σ ln(leak), for the mean in dB
  mutable double leak_sum_ = 0.0, leak_compensation_ = 0.0;

  // Lock tracking.
  mutable bool below_ = false;
  mutable double below_since_s_ = NAN;
  mutable std::optional<double> first_lock_s_;
  mutable int64_t excursions_ = 0;
  mutable int64_t threshold_crossings_ = 0;
  mutable bool armed_ = false;  ///< the error fell below half the threshold since the last excursion
  double rearm_rad_;            ///< half the lock threshold

  // Recovery (in the error window).
  mutable bool above_recovery_ = false;
  mutable double above_recovery_since_s_ = NAN;
  mutable int64_t recovery_stretches_ = 0;
  mutable double longest_recovery_s_ = 0.0;
  mutable double longest_recovery_from_s_ = NAN;

  // Controls and controller.
  mutable std::vector<LogHistogram> phi_;
  UpdateTally updates_;
};

inline void RunStatistics::AddSample(double t_s, const StokesVector& s_out,
                              const double* phi_applied) {
  const int i = pending_;
  pending_t_s_[i] = t_s;
  PendOutput(i, s_out[0], s_out[1], s_out[2]);
  double* phi = pending_phi_.data() + static_cast<ptrdiff_t>(pending_phi_rows_++) * phi_stride_;
  DispatchCount(control_count_, [&](auto fixed) {
    const int count = FixedOr(fixed, control_count_);
    for (int c = 0; c < count; ++c) phi[c] = phi_applied[c];
  });
  if (++pending_ == kBatch) Flush();
}

}  // namespace dpc
