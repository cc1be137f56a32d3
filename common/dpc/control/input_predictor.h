#pragma once
// Predicts the input SOP ahead of its latest measurement from its recent history: a recursive
// least-squares fit of the full rotation (three degrees of freedom) that carries each sample to
// the next, then that rotation extrapolated over the horizon.
//
// Model. Any rotation with angle θ about the unit axis r̂ has the Gibbs vector ρ = tan(θ/2)·r̂,
// and for every vector it turns, exactly (Rodrigues / Cayley),
//
//   S_k − S_(k−1) = ρ × (S_k + S_(k−1)).
//
// With interval τ_k (in nominal sample periods; 1 for equally spaced samples) the rotation per
// nominal period is modelled by w with ρ_k = (τ_k/2)·w, linear in w:
//
//   y_k = w × a_k,   y_k = S_k − S_(k−1),   a_k = (τ_k/2)(S_k + S_(k−1)).
//
// Least squares with exponential forgetting (time constant W nominal periods, weight
// f_k = exp(−τ_k/W) on the past), as running weighted averages:
//
//   A ← f A + (1 − f)(|a|² I − a aᵀ),   b ← f b + (1 − f)(a × y),   w = (A + εI)⁻¹ b
//
// ([a×]ᵀ[a×] = |a|²I − aaᵀ and −[a×]ᵀy = a × y; ε = 1e-9·tr A keeps the direction along a
// slowly moving S, which the data hardly constrain, bounded). For equally spaced samples and a
// constant rotation the fit is exact: |w| = 2 tan(θ/2), so the angle per nominal period is
// θ = 2·atan(|w|/2) (used for any spacing). The prediction h nominal periods after the latest
// sample turns it by h·θ about ŵ (paper eq. 1):
//
//   Ŝ(t_k + h) = Rot(ŵ, h·θ) S_k.
//
// Floor. What no predictor can know is the part of the input that is not yet determined at
// t_k. For the paper's scrambler (rotation at ω plus an independent N(0, σ²) kick about S2 on
// every sample), the kicks of the D samples of the horizon: ≈ 0.63·σ·√D on the sphere on average
// over the orbit (paper_scrambler.h; σ = ω·dt: 0.51° at 100 krad/s, 50 MHz, D = 50). A fit over
// a window of W samples adds an error of the rate of order σ·h/√W (≈ 0.2° for W = 1000).
//
// Cost. Observing is ~30 flops (normalization, the running averages). Solving the fit (3 × 3
// cofactors), the angle (atan) and the rotation over the horizon (sin, cos) cost several times
// that, so a prediction reuses the rotation matrix of the latest solve for the same horizon
// for up to `refresh_samples` observations (default 16, against a fit memory of ~1000): then
// it is one 3 × 3 product per sample, and every refresh_samples-th prediction pays for the
// solve. A different horizon (the DDS controller's measured latency) solves at once.
//
// Real-time: Observe, ObserveAt and Predict* do not allocate (fixed-size state). A single
// predictor is not thread-safe (the prediction's cache is mutable).

#include <cmath>
#include <cstdint>

#include "dpc/optics/stokes.h"

namespace dpc {

class InputPredictor {
 public:
  /// `window_samples` W > 0: the memory time constant, in nominal sample periods.
  /// `nominal_sample_period_s` > 0: the nominal sample period (for ObserveAt and
  /// PredictSeconds; 1 when the predictor is used in samples only). Throws std::invalid_argument
  /// for non-finite or non-positive values.
  /// `refresh_samples` ≥ 1: observations between solves of the fit for the same horizon (1:
  /// every prediction solves). Throws std::invalid_argument for bad values.
  explicit InputPredictor(double window_samples, double nominal_sample_period_s = 1.0,
                          int refresh_samples = kDefaultRefreshSamples);

  static constexpr int kDefaultRefreshSamples = 64;

  /// Not real-time. Forgets every sample.
  void Reset();

  /// Real-time. Adds the sample one nominal period after the previous one. A non-finite or
  /// zero-length sample is ignored (returns false); the sample is normalized.
  bool Observe(const StokesVector& s);

  /// Real-time. Adds a sample taken at t_s (seconds, increasing). A sample at or before the
  /// previous one's time, or non-finite, is ignored (returns false).
  bool ObserveAt(const StokesVector& s, double t_s);

  /// Real-time. The SOP predicted `horizon_samples` nominal periods after the latest sample
  /// (any real horizon ≥ 0; the latest sample itself before two samples have been seen).
  StokesVector PredictSamples(double horizon_samples) const;

  /// Real-time. The SOP predicted `horizon_s` seconds after the latest sample's time.
  StokesVector PredictSeconds(double horizon_s) const {
    return PredictSamples(horizon_s / nominal_sample_period_s_);
  }

  /// Real-time. The fitted rotation per nominal period: axis ŵ times the angle θ (rad).
  Vector3 RotationPerSample() const;
  /// The fitted rotation rate, rad/s (|rotation per sample| / nominal period).
  double RateRadPerS() const { return RotationPerSample().norm() / nominal_sample_period_s_; }

  /// The latest sample (normalized).
  const StokesVector& latest() const { return latest_; }
  /// Samples accepted since construction or Reset.
  int64_t samples() const { return samples_; }
  double window_samples() const { return window_samples_; }
  double nominal_sample_period_s() const { return nominal_sample_period_s_; }

 private:
  /// Adds the interval from the latest sample to `s` (already normalized), τ in nominal periods.
  void AddInterval(const StokesVector& s, double tau);
  /// Solves the fit and caches the rotation over `horizon_samples`.
  void Refresh(double horizon_samples) const;

  double window_samples_;
  double nominal_sample_period_s_;
  double uniform_forget_;  ///< exp(−1/W), the weight of the past for τ = 1
  // Weighted averages: A (symmetric, 6 entries: xx yy zz xy xz yz) and b.
  double a_xx_ = 0, a_yy_ = 0, a_zz_ = 0, a_xy_ = 0, a_xz_ = 0, a_yz_ = 0;
  Vector3 b_ = Vector3::Zero();
  StokesVector latest_ = StokesVector::UnitX();
  double latest_t_s_ = 0.0;
  int64_t samples_ = 0;
  int refresh_samples_;
  // The cached prediction rotation (mutable: PredictSamples is logically const).
  mutable double cached_horizon_samples_ = -1.0;
  mutable int since_refresh_ = 0;
  mutable Matrix3 cached_rotation_ = Matrix3::Identity();
};

// ---- Real-time paths, inline: they run on every sample.

/// `s` scaled to unit length; false if it has none (zero, NaN, Inf). Near unit length (what a
/// polarimeter reports) one Newton step for 1/|s| (error 3/8·(|s|² − 1)², < 4e-9 here) instead
/// of a square root and a division.
inline bool NormalizeStokes(const StokesVector& s, StokesVector* unit) {
  const double r2 = s.squaredNorm();
  if (std::abs(r2 - 1.0) < 1e-4) {
    *unit = s * (1.5 - 0.5 * r2);
    return true;
  }
  if (!std::isfinite(r2) || !(r2 > 0.0)) return false;
  *unit = s / std::sqrt(r2);
  return true;
}

inline bool InputPredictor::Observe(const StokesVector& s) {
  StokesVector unit;
  if (!NormalizeStokes(s, &unit)) return false;
  if (samples_ > 0) AddInterval(unit, 1.0);
  latest_ = unit;
  latest_t_s_ += nominal_sample_period_s_;
  ++samples_;
  ++since_refresh_;
  return true;
}

inline void InputPredictor::AddInterval(const StokesVector& s, double tau) {
  const double f = tau == 1.0 ? uniform_forget_ : std::exp(-tau / window_samples_);
  const double g = 1.0 - f;
  const double half = 0.5 * tau;
  const double ax = half * (s[0] + latest_[0]), ay = half * (s[1] + latest_[1]),
               az = half * (s[2] + latest_[2]);
  const double yx = s[0] - latest_[0], yy = s[1] - latest_[1], yz = s[2] - latest_[2];
  const double xx = ax * ax, yy2 = ay * ay, zz = az * az;
  // |a|²I − aaᵀ and a × y.
  a_xx_ = f * a_xx_ + g * (yy2 + zz);
  a_yy_ = f * a_yy_ + g * (xx + zz);
  a_zz_ = f * a_zz_ + g * (xx + yy2);
  a_xy_ = f * a_xy_ - g * (ax * ay);
  a_xz_ = f * a_xz_ - g * (ax * az);
  a_yz_ = f * a_yz_ - g * (ay * az);
  b_[0] = f * b_[0] + g * (ay * yz - az * yy);
  b_[1] = f * b_[1] + g * (az * yx - ax * yz);
  b_[2] = f * b_[2] + g * (ax * yy - ay * yx);
}

inline StokesVector InputPredictor::PredictSamples(double horizon_samples) const {
  if (samples_ < 2 || !(horizon_samples > 0.0)) return latest_;
  if (horizon_samples != cached_horizon_samples_ || since_refresh_ >= refresh_samples_) {
    Refresh(horizon_samples);
  }
  return cached_rotation_ * latest_;
}

}  // namespace dpc
