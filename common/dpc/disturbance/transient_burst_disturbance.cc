#include "dpc/disturbance/transient_burst_disturbance.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dpc/optics/rotation.h"

namespace dpc {

TransientBurstDisturbance::TransientBurstDisturbance(double start_s, double duration_s,
                                                     double peak_rate_rad_per_s, double period_s,
                                                     Envelope envelope,
                                                     std::optional<Vector3> axis,
                                                     double sample_rate_hz)
    : start_s_(start_s),
      duration_s_(duration_s),
      peak_rate_rad_per_s_(peak_rate_rad_per_s),
      period_s_(period_s),
      envelope_(envelope),
      random_axis_(!axis.has_value()),
      sample_period_s_(SamplePeriodFromRate(sample_rate_hz, "transient burst")),
      axis_(axis ? NormalizedAxis(*axis, "transient burst: axis") : Vector3::Zero()) {
  if (!std::isfinite(start_s)) {
    throw std::invalid_argument(fmt::format("transient burst: start_s = {} is not finite", start_s));
  }
  if (!std::isfinite(duration_s) || !(duration_s > 0.0)) {
    throw std::invalid_argument(
        fmt::format("transient burst: duration_s = {} must be finite and > 0", duration_s));
  }
  RequireNonNegativeFinite(peak_rate_rad_per_s, "transient burst: rate_rad_per_s (peak)");
  if (!(period_s == 0.0 || (std::isfinite(period_s) && period_s >= duration_s))) {
    throw std::invalid_argument(fmt::format(
        "transient burst: period_s = {} must be 0 (one burst) or finite and >= duration_s = {} "
        "(bursts must not overlap)",
        period_s, duration_s));
  }
  if (envelope != Envelope::kRectangular && envelope != Envelope::kHalfSine) {
    throw std::invalid_argument("transient burst: unknown envelope");
  }
}

int64_t TransientBurstDisturbance::BurstIndexAt(double t_s) const {
  if (t_s < start_s_) return -1;
  int64_t k = 0;
  if (period_s_ > 0.0) k = static_cast<int64_t>(std::floor((t_s - start_s_) / period_s_));
  // The division may round across a window edge: settle on the window that holds t_s.
  for (int64_t candidate : {k - 1, k, k + 1}) {
    if (candidate < 0 || (candidate > 0 && period_s_ == 0.0)) continue;
    const double begin_s = start_s_ + static_cast<double>(candidate) * period_s_;
    if (t_s >= begin_s && t_s < begin_s + duration_s_) return candidate;
  }
  return -1;
}

double TransientBurstDisturbance::BurstAngleRad(double tau_begin_s, double tau_end_s) const {
  if (envelope_ == Envelope::kRectangular) {
    return peak_rate_rad_per_s_ * (tau_end_s - tau_begin_s);
  }
  const double half_pi_over_duration = 0.5 * M_PI / duration_s_;
  return peak_rate_rad_per_s_ * (2.0 * duration_s_ / M_PI) *
         std::sin(half_pi_over_duration * (tau_begin_s + tau_end_s)) *
         std::sin(half_pi_over_duration * (tau_end_s - tau_begin_s));
}

void TransientBurstDisturbance::ApplyBurst(int64_t k, double begin_s, double end_s,
                                           StokesVector* sop, RandomSource& random) {
  const double burst_start_s = start_s_ + static_cast<double>(k) * period_s_;
  const double tau_begin_s = std::max(begin_s, burst_start_s) - burst_start_s;
  const double tau_end_s = std::min(end_s, burst_start_s + duration_s_) - burst_start_s;
  if (!(tau_end_s > tau_begin_s)) return;
  if (random_axis_ && k != axis_burst_index_) {
    axis_ = random.UnitVector();
    axis_burst_index_ = k;
  }
  double sin_angle, cos_angle;
  SinCos(BurstAngleRad(tau_begin_s, tau_end_s), &sin_angle, &cos_angle);
  *sop = RotateVector(axis_, cos_angle, sin_angle, *sop);
}

void TransientBurstDisturbance::Advance(double t_s, StokesVector* sop, RandomSource& random) {
  const double end_s = t_s + sample_period_s_;
  if (end_s <= start_s_) return;  // before the first burst
  if (period_s_ == 0.0) {
    ApplyBurst(0, t_s, end_s, sop, random);
    return;
  }
  // Bursts k with t_k < end_s and t_k + T > t_s. Burst k − 1 of the floor ended by t_k ≤ t_s
  // (period ≥ T), but start one earlier in case the division rounded up.
  int64_t k = static_cast<int64_t>(std::floor((t_s - start_s_) / period_s_)) - 1;
  if (k < 0) k = 0;
  for (; start_s_ + static_cast<double>(k) * period_s_ < end_s; ++k) {
    ApplyBurst(k, t_s, end_s, sop, random);
  }
}

std::string TransientBurstDisturbance::Describe() const {
  const std::string axis = random_axis_ ? std::string("a random axis per burst")
                                        : "axis " + FormatStokes(axis_);
  const std::string repeat =
      period_s_ > 0.0 ? fmt::format("every {:g} s", period_s_) : std::string("once");
  return fmt::format("transient burst: {} envelope, peak {:g} rad/s for {:g} s from {:g} s, {}, "
                     "about {}",
                     envelope_ == Envelope::kRectangular ? "rectangular" : "half-sine",
                     peak_rate_rad_per_s_, duration_s_, start_s_, repeat, axis);
}

}  // namespace dpc
