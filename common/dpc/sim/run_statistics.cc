#include "dpc/sim/run_statistics.h"

#include "dpc/optics/count_dispatch.h"
#include "dpc/optics/rotation.h"

#include <algorithm>
#include <cmath>

namespace dpc {
namespace {

constexpr double kLeakFloor = 1e-20;  // −200 dB: below the round-off of 1 − S·S*
constexpr double kRadToDeg = 180.0 / M_PI;
// 10·log10(x) = (10 / ln 10)·ln(x).
constexpr double kDecibelsPerNeper = 4.3429448190325182765;

// Compensated summation step: Knuth's TwoSum recovers the rounding error of *sum + value
// exactly, without a branch.
inline void CompensatedAdd(double value, double* sum, double* compensation) {
  const double total = *sum + value;
  const double value_part = total - *sum;
  *compensation += (*sum - (total - value_part)) + (value - value_part);
  *sum = total;
}

}  // namespace

RunStatistics::RunStatistics(const Target& target, int control_count, double activation_s,
                             double lock_threshold_deg, std::optional<double> statistics_start_s,
                             double settle_s)
    : target_(target),
      point_target_(target.is_point()),
      target_x_(target.point()[0]),
      target_y_(target.point()[1]),
      target_z_(target.point()[2]),
      control_count_(control_count),
      activation_s_(activation_s),
      lock_threshold_rad_(lock_threshold_deg / kRadToDeg),
      fixed_start_s_(statistics_start_s),
      settle_s_(settle_s),
      pending_phi_(static_cast<size_t>(kBatch) * static_cast<size_t>(std::max(4, control_count))),
      phi_stride_(std::max(4, control_count)),
      error_deg_(1e-12, 360.0) {
  rearm_rad_ = 0.5 * lock_threshold_rad_;
  phi_.reserve(control_count);
  for (int c = 0; c < control_count; ++c) phi_.emplace_back(1e-12, 1e12);
}

void RunStatistics::AddSamples(int64_t first_sample, double sample_period_s, int count,
                               const double* const* s_out, std::ptrdiff_t stride) {
  for (int done = 0; done < count;) {
    // Up to the end of the buffer; the loops below have no other exit (they vectorize).
    const int n = std::min(count - done, kBatch - pending_);
    const std::ptrdiff_t from = static_cast<std::ptrdiff_t>(done) * stride;
    const double *x = s_out[0] + from, *y = s_out[1] + from, *z = s_out[2] + from;
    for (int i = 0; i < n; ++i) {
      pending_t_s_[pending_ + i] = static_cast<double>(first_sample + done + i) * sample_period_s;
    }
    for (int i = 0; i < n; ++i) {
      const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(i) * stride;
      PendOutput(pending_ + i, x[at], y[at], z[at]);
    }
    pending_ += n;
    done += n;
    if (pending_ == kBatch) Flush();
  }
}

void RunStatistics::AddControls(RunStatistics* const* statistics, int runs,
                                const double* const* phi, int count, std::ptrdiff_t row_stride) {
  for (int c = 0; c < statistics[0]->control_count_; ++c) {
    LogHistogram* histograms[8] = {};
    for (int j = 0; j < runs; ++j) histograms[j] = &statistics[j]->phi_[static_cast<size_t>(c)];
    if (runs > 4) {
      LogHistogram::AddBatchLanes8(histograms, runs, phi[c], count, row_stride);
    } else {
      LogHistogram::AddBatchLanes(histograms, runs, phi[c], count, row_stride);
    }
  }
}

void RunStatistics::Flush() const {
  const int count = pending_;
  if (count == 0) return;
  pending_ = 0;
  // Independent per sample: the expensive part, pipelined across the batch.
  double error_rad[kBatch], leak[kBatch];
  if (point_target_) {
    // Target::DistanceAndLeak from the chord c = |S − S*| = 2 sin(α/2); past 90° from the
    // supplementary chord |S + S*|² = 4 − c² (unit vectors), within ~1e-10 rad even near 180°.
    // First the series for every sample (vectorizes), then the library for the few beyond it.
    int beyond = 0;  // an integer OR: a reduction the compiler vectorizes
    for (int i = 0; i < count; ++i) {
      const double half_chord = 0.5 * std::sqrt(pending_chord_squared_[i]);
      leak[i] = 0.25 * pending_chord_squared_[i];
      error_rad[i] = 2.0 * SmallArcSine(half_chord);
      beyond |= half_chord > kSmallArcSineLimit;
    }
    for (int i = 0; beyond && i < count; ++i) {
      const double chord_squared = pending_chord_squared_[i];
      if (chord_squared <= 4.0 * kSmallArcSineLimit * kSmallArcSineLimit) continue;
      if (chord_squared <= 2.0) {
        error_rad[i] = 2.0 * std::asin(0.5 * std::sqrt(chord_squared));
      } else {
        const double supplementary_squared = std::max(0.0, 4.0 - chord_squared);
        leak[i] = std::min(1.0, 0.25 * chord_squared);
        error_rad[i] = M_PI - 2.0 * std::asin(0.5 * std::sqrt(supplementary_squared));
      }
    }
  } else {
    for (int i = 0; i < count; ++i) {
      const StokesVector s_out(pending_s_out_[i][0], pending_s_out_[i][1], pending_s_out_[i][2]);
      target_.DistanceAndLeak(s_out, &error_rad[i], &leak[i]);
    }
  }
  // In time order: lock tracking and the error window.
  double window_error_deg[kBatch], window_leak[kBatch], window_raw_leak[kBatch], window_t_s[kBatch];
  // The window's times and raw leaks: the arrays above, or the batch's own when all of it is in.
  const double* window_times_s = window_t_s;
  const double* window_raw_leaks = window_raw_leak;
  int window_count = 0;
  // The usual batch of a locked run: already below the threshold, the window open, and every
  // sample below the threshold. Nothing changes state but the rearming, and the whole batch is
  // in the window: branch-free loops (they vectorize) instead of the sample-by-sample pass.
  int above = 1, rearms = 0;  // integer ORs: reductions the compiler vectorizes
  if (below_ && window_open_) {
    above = 0;
    for (int i = 0; i < count; ++i) {
      above |= !(error_rad[i] < lock_threshold_rad_);
      rearms |= error_rad[i] < rearm_rad_;
    }
  }
  if (above == 0) {
    armed_ = armed_ || rearms != 0;
    window_end_s_ = pending_t_s_[count - 1];
    for (int i = 0; i < count; ++i) {
      window_error_deg[i] = error_rad[i] * kRadToDeg;
      window_leak[i] = std::max(leak[i], kLeakFloor);
    }
    window_times_s = pending_t_s_;
    window_raw_leaks = leak;
    window_count = count;
  } else {
    for (int i = 0; i < count; ++i) {
      const double t_s = pending_t_s_[i];
      const bool below = error_rad[i] < lock_threshold_rad_;
      if (below && !below_) {
        below_since_s_ = t_s;
        if (!first_lock_s_) first_lock_s_ = t_s;
      } else if (!below && below_) {
        ++threshold_crossings_;
        if (armed_) {
          ++excursions_;
          armed_ = false;
        }
      }
      if (error_rad[i] < rearm_rad_) armed_ = true;
      below_ = below;
      if (!window_open_) {
        window_open_ = fixed_start_s_ ? t_s >= *fixed_start_s_
                                      : first_lock_s_.has_value() && t_s >= *first_lock_s_ + settle_s_;
        if (window_open_) window_start_s_ = t_s;
      }
      if (window_open_) {
        window_end_s_ = t_s;
        window_t_s[window_count] = t_s;
        window_error_deg[window_count] = error_rad[i] * kRadToDeg;
        window_leak[window_count] = std::max(leak[i], kLeakFloor);
        window_raw_leak[window_count] = leak[i];
        ++window_count;
      }
    }
  }
  // Both branches above fill the window arrays up to window_count; GCC 12 cannot see it
  // through the steady branch's vectorized loop.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  TrackRecovery(window_error_deg, window_times_s, window_count);
#pragma GCC diagnostic pop
  leak_log_sum_.AddBatch(window_leak, window_count);
  // Blocked sum: plain within the batch (even and odd window samples in two registers; an
  // array indexed by parity would chain through memory), compensated across batches.
  double even = 0.0, odd = 0.0;
  int w = 0;
  for (; w + 1 < window_count; w += 2) {
    even += window_raw_leaks[w];
    odd += window_raw_leaks[w + 1];
  }
  if (w < window_count) even += window_raw_leaks[w];
  CompensatedAdd(even + odd, &leak_sum_, &leak_compensation_);
  error_deg_.AddBatch(window_error_deg, window_count);
  // Controls (AddSample's): up to four histograms at once, more one at a time.
  const int rows = pending_phi_rows_;
  pending_phi_rows_ = 0;
  if (rows == 0) return;
  if (control_count_ <= 4) {
    LogHistogram* histograms[4] = {};
    for (int c = 0; c < control_count_; ++c) histograms[c] = &phi_[c];
    LogHistogram::AddBatchLanes(histograms, control_count_, pending_phi_.data(), rows);
  } else {
    for (int c = 0; c < control_count_; ++c) {
      phi_[c].AddBatch(pending_phi_.data() + c, rows, phi_stride_);
    }
  }
}

void RunStatistics::TrackRecovery(const double* error_deg, const double* t_s, int count) const {
  if (count == 0) return;
  // Stretches change rarely (a few per thousand samples on the paper's scrambler): first an
  // integer OR over the batch (it vectorizes) of "differs from the sample before", and the
  // sample-by-sample pass only for a batch with a change in it.
  int changes = (error_deg[0] >= kRecoveryThresholdDeg) != above_recovery_;
  for (int i = 1; i < count; ++i) {
    changes |= (error_deg[i] >= kRecoveryThresholdDeg) != (error_deg[i - 1] >= kRecoveryThresholdDeg);
  }
  if (changes == 0) return;
  bool above = above_recovery_;
  double since_s = above_recovery_since_s_;
  for (int i = 0; i < count; ++i) {
    const bool now_above = error_deg[i] >= kRecoveryThresholdDeg;
    if (now_above == above) continue;
    above = now_above;
    if (above) {
      since_s = t_s[i];
      ++recovery_stretches_;
    } else if (t_s[i] - since_s > longest_recovery_s_) {
      longest_recovery_s_ = t_s[i] - since_s;
      longest_recovery_from_s_ = since_s;
    }
  }
  above_recovery_ = above;
  above_recovery_since_s_ = since_s;
}

RunSummary RunStatistics::Summarize(int64_t samples, int64_t resets) const {
  Flush();
  RunSummary s;
  s.samples = samples;
  s.statistics_samples = error_deg_.count();
  s.statistics_start_s = window_start_s_;
  s.statistics_end_s = window_end_s_;
  if (error_deg_.count() > 0) {
    s.error_deg = {error_deg_.mean(), error_deg_.Percentile(50.0), error_deg_.Percentile(99.0),
                   error_deg_.max()};
    const double n = static_cast<double>(error_deg_.count());
    s.extinction_db_mean = kDecibelsPerNeper * leak_log_sum_.LogSum() / n;
    s.extinction_db_power_mean =
        10.0 * std::log10(std::max((leak_sum_ + leak_compensation_) / n, kLeakFloor));
  } else {
    s.error_deg = {NAN, NAN, NAN, NAN};
    s.extinction_db_mean = s.extinction_db_power_mean = NAN;
  }
  // A run with a current sub-threshold stretch is locked since that stretch began.
  if (below_) s.lock_time_s = below_since_s_ - activation_s_;
  if (first_lock_s_) s.first_lock_time_s = *first_lock_s_ - activation_s_;
  s.excursions = excursions_;
  s.threshold_crossings = threshold_crossings_;
  s.recovery_stretches = recovery_stretches_;
  s.longest_recovery_s = longest_recovery_s_;
  s.longest_recovery_from_s = longest_recovery_from_s_;
  // A stretch still above at the end lasts until the window's last sample.
  if (above_recovery_ && window_end_s_ - above_recovery_since_s_ > s.longest_recovery_s) {
    s.longest_recovery_s = window_end_s_ - above_recovery_since_s_;
    s.longest_recovery_from_s = above_recovery_since_s_;
  }
  for (const auto& h : phi_) {
    s.phi_min.push_back(h.count() ? h.min() : NAN);
    s.phi_max.push_back(h.count() ? h.max() : NAN);
    s.phi_p1.push_back(h.count() ? h.Percentile(1.0) : NAN);
    s.phi_p99.push_back(h.count() ? h.Percentile(99.0) : NAN);
  }
  const UpdateTally& u = updates_;
  const double updates = static_cast<double>(u.updates);
  s.updates = u.updates;
  s.nullspace_active_fraction = u.updates ? static_cast<double>(u.nullspace_active) / updates : 0.0;
  s.failed_updates = u.failed;
  s.rank_deficient_updates = u.rank_deficient;
  s.clamped_updates = u.clamped;
  s.resets = resets;
  s.sigma_min_min = u.updates ? std::sqrt(u.min_sigma_squared) : NAN;
  s.near_singular_fraction = u.updates ? static_cast<double>(u.near_singular) / updates : 0.0;
  return s;
}

}  // namespace dpc
