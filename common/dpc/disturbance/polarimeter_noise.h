#pragma once
// Polarimeter noise: a measured SOP is the true SOP displaced by a small random rotation.
//
// For a unit s, with (e1, e2) = TangentBasis(s) and n1, n2 ~ N(0, 1) independent:
//
//   v  = σ·(n1·e1 + n2·e2)                         (a tangent vector at s)
//   s' = s·cos|v| + (v/|v|)·sin|v|                 (s moved by |v| along the geodesic toward v)
//
// σ in radians (given in degrees). The angular error |v| is Rayleigh-distributed with scale σ
// (mean σ·√(π/2), RMS σ·√2) and its direction is uniform; s' is unit when s is. σ = 0 returns
// s unchanged and draws nothing. Draws come from RandomSource(seed, stream), independent of
// the input SOP's stream (1); a bench with two polarimeters gives each its own stream.

#include <cstdint>

#include "dpc/disturbance/random_source.h"
#include "dpc/optics/rotation.h"
#include "dpc/optics/stokes.h"

namespace dpc {

class PolarimeterNoise {
 public:
  /// The default RandomSource stream of the noise.
  static constexpr uint64_t kRandomStream = 2;

  /// `sigma_deg` finite and ≥ 0. Throws std::invalid_argument otherwise.
  PolarimeterNoise(double sigma_deg, uint64_t seed, uint64_t stream = kRandomStream);

  /// Real-time. A noisy reading of the unit Stokes vector `s`: two normal draws when σ > 0.
  StokesVector Measure(const StokesVector& s) {
    if (sigma_rad_ == 0.0) return s;  // inlined: a noiseless polarimeter costs a compare
    return MeasureNoisy(s);
  }

  double sigma_deg() const { return sigma_deg_; }
  double sigma_rad() const { return sigma_rad_; }

 private:
  [[gnu::noinline]] StokesVector MeasureNoisy(const StokesVector& s) {
    const double n1 = random_.Normal(), n2 = random_.Normal();
    const double norm = std::sqrt(n1 * n1 + n2 * n2);
    if (!(norm > 0.0)) return s;
    Vector3 e1, e2;
    TangentBasis(s, &e1, &e2);
    double sin_angle, cos_angle;
    SinCos(sigma_rad_ * norm, &sin_angle, &cos_angle);
    return cos_angle * s + (sin_angle / norm) * (n1 * e1 + n2 * e2);
  }

  double sigma_deg_;
  double sigma_rad_;
  RandomSource random_;
};

}  // namespace dpc
