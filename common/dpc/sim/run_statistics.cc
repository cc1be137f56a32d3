#include "dpc/sim/run_statistics.h"

#include <cmath>

namespace dpc {
namespace {

constexpr double kLeakFloor = 1e-20;  // −200 dB: below the round-off of 1 − S·S*
constexpr double kRadToDeg = 180.0 / M_PI;

// Kahan–Babuška summation step.
inline void CompensatedAdd(double value, double* sum, double* compensation) {
  const double t = *sum + value;
  if (std::abs(*sum) >= std::abs(value)) {
    *compensation += (*sum - t) + value;
  } else {
    *compensation += (value - t) + *sum;
  }
  *sum = t;
}

}  // namespace

RunStatistics::RunStatistics(int control_count, double activation_s, double lock_threshold_deg,
                             std::optional<double> statistics_start_s)
    : activation_s_(activation_s),
      lock_threshold_rad_(lock_threshold_deg / kRadToDeg),
      fixed_start_s_(statistics_start_s),
      error_deg_(1e-12, 360.0),
      sigma_min_(1e-15, 1e6) {
  phi_.reserve(control_count);
  for (int c = 0; c < control_count; ++c) phi_.emplace_back(1e-12, 1e12);
}

void RunStatistics::AddSample(double t_s, double error_rad, double leak,
                              const ControlVector& phi_applied) {
  // Lock tracking.
  const bool below = error_rad < lock_threshold_rad_;
  if (below && !below_) {
    below_since_s_ = t_s;
    if (!first_lock_s_) first_lock_s_ = t_s;
  } else if (!below && below_) {
    ++excursions_;
  }
  below_ = below;

  // Error window.
  if (!window_open_) {
    window_open_ = fixed_start_s_ ? t_s >= *fixed_start_s_ : first_lock_s_.has_value();
    if (window_open_) window_start_s_ = t_s;
  }
  if (window_open_) {
    error_deg_.Add(error_rad * kRadToDeg);
    CompensatedAdd(10.0 * std::log10(std::max(leak, kLeakFloor)), &leak_db_sum_,
                   &leak_db_compensation_);
    CompensatedAdd(leak, &leak_sum_, &leak_compensation_);
  }

  for (size_t c = 0; c < phi_.size(); ++c) phi_[c].Add(phi_applied[static_cast<int>(c)]);
}

void RunStatistics::AddUpdate(bool nullspace_active, bool failed, bool rank_deficient,
                              bool clamped, double sigma_min) {
  ++updates_;
  nullspace_active_ += nullspace_active;
  failed_ += failed;
  rank_deficient_ += rank_deficient;
  clamped_ += clamped;
  sigma_min_.Add(sigma_min);
}

RunSummary RunStatistics::Summarize(int64_t samples, int64_t resets) const {
  RunSummary s;
  s.samples = samples;
  s.statistics_samples = error_deg_.count();
  s.statistics_start_s = window_start_s_;
  if (error_deg_.count() > 0) {
    s.error_deg = {error_deg_.mean(), error_deg_.Percentile(50.0), error_deg_.Percentile(99.0),
                   error_deg_.max()};
    const double n = static_cast<double>(error_deg_.count());
    s.extinction_db_mean = (leak_db_sum_ + leak_db_compensation_) / n;
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
  for (const auto& h : phi_) {
    s.phi_min.push_back(h.count() ? h.min() : NAN);
    s.phi_max.push_back(h.count() ? h.max() : NAN);
    s.phi_p1.push_back(h.count() ? h.Percentile(1.0) : NAN);
    s.phi_p99.push_back(h.count() ? h.Percentile(99.0) : NAN);
  }
  s.updates = updates_;
  s.nullspace_active_fraction =
      updates_ ? static_cast<double>(nullspace_active_) / static_cast<double>(updates_) : 0.0;
  s.failed_updates = failed_;
  s.rank_deficient_updates = rank_deficient_;
  s.clamped_updates = clamped_;
  s.resets = resets;
  s.sigma_min_min = sigma_min_.count() ? sigma_min_.min() : NAN;
  s.sigma_min_p1 = sigma_min_.count() ? sigma_min_.Percentile(1.0) : NAN;
  return s;
}

}  // namespace dpc
