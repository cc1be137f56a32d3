#pragma once
// Transient bursts of fast SOP rotation, as lightning strikes on aerial fibre cause (rates up to
// ~5 Mrad/s for tens of µs to ms).
//
// Burst k (k = 0, 1, 2, …; only k = 0 when the period is 0) is active for
//
//   t ∈ [t_k, t_k + T),   t_k = start + k·period,   T = duration,
//
// and rotates the SOP about its axis at the rate ω(t) = peak · e((t − t_k)/T) with the envelope
//
//   rectangular:  e(x) = 1
//   half-sine:    e(x) = sin(π·x)
//
// The axis is either fixed, or a new uniformly random direction drawn when a burst first
// overlaps a sample (one RandomSource::UnitVector() per burst).
//
// Per sample [t, t + dt) the SOP rotates by the exact integral of the rate over the part of the
// sample inside each burst, with τa, τb the ends of that overlap relative to t_k:
//
//   rectangular:  Δθ = peak · (τb − τa)
//   half-sine:    Δθ = peak·(T/π)·(cos(πτa/T) − cos(πτb/T))
//                    = peak·(2T/π)·sin(π(τa + τb)/(2T))·sin(π(τb − τa)/(2T))
//
// so a whole burst turns the SOP by exactly peak·T (rectangular) or peak·T·2/π (half-sine),
// whatever its alignment with the sample grid, and a burst shorter than a sample still acts.
// Outside bursts the SOP does not change and nothing is drawn.
//
// Timing assumption: Advance is called with non-decreasing t (a random axis is redrawn when
// the burst index changes).

#include <cstdint>
#include <optional>
#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/disturbance.h"

namespace dpc {

class TransientBurstDisturbance final : public Disturbance {
 public:
  using Envelope = DisturbanceConfig::Envelope;

  /// `start_s` finite; `duration_s` T finite and > 0; `peak_rate_rad_per_s` finite and ≥ 0;
  /// `period_s` 0 (a single burst) or finite and ≥ duration_s (bursts do not overlap); `axis`
  /// finite and non-zero (normalized), or std::nullopt for a random axis per burst;
  /// `sample_rate_hz` finite and > 0. Throws std::invalid_argument otherwise.
  TransientBurstDisturbance(double start_s, double duration_s, double peak_rate_rad_per_s,
                            double period_s, Envelope envelope, std::optional<Vector3> axis,
                            double sample_rate_hz);

  /// Real-time. Rotates *sop by each burst's integrated rate over [t_s, t_s + dt). Cost O(1)
  /// outside bursts; O(1 + dt/period) inside.
  void Advance(double t_s, StokesVector* sop, RandomSource& random) override;

  std::string Describe() const override;

  /// The burst index k whose window [t_k, t_k + T) contains t_s, or −1 if none.
  int64_t BurstIndexAt(double t_s) const;

  double start_s() const { return start_s_; }
  double duration_s() const { return duration_s_; }
  double peak_rate_rad_per_s() const { return peak_rate_rad_per_s_; }
  double period_s() const { return period_s_; }
  Envelope envelope() const { return envelope_; }
  bool random_axis() const { return random_axis_; }
  /// The fixed axis, or the axis of the latest burst (random axes; zero before the first).
  const Vector3& current_axis() const { return axis_; }

 private:
  /// The rotation angle of burst k over the overlap [τa, τb] (relative to t_k), 0 ≤ τa < τb ≤ T.
  double BurstAngleRad(double tau_begin_s, double tau_end_s) const;
  /// Rotates *sop by burst k over the absolute window [begin, end) if it overlaps it.
  void ApplyBurst(int64_t k, double begin_s, double end_s, StokesVector* sop,
                  RandomSource& random);

  double start_s_;
  double duration_s_;
  double peak_rate_rad_per_s_;
  double period_s_;
  Envelope envelope_;
  bool random_axis_;
  double sample_period_s_;
  Vector3 axis_;
  int64_t axis_burst_index_ = -1;  ///< the burst that drew axis_ (random axes)
};

}  // namespace dpc
