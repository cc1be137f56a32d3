#pragma once
// Isotropic rotational diffusion of the SOP on the Poincaré sphere (a slowly drifting fibre).
//
// Per sample (dt = 1/fs) a rotation by the rotation vector v (angle |v| about v/|v|):
//
//   S ← Rot(v/|v|, |v|) · S,      v ~ N(0, D²·dt·I₃)
//
// D in rad/√s. The per-sample rotations are independent and isotropic, so the process has no
// preferred axis. For short times the SOP's squared angular displacement has mean
// E[θ²] ≈ 2·D²·t (two tangent dimensions), and at any time E[S(t)·S(0)] = λ^N after N samples
// with λ = 1/3 + (2/3)(1 − σ²)·exp(−σ²/2), σ² = D²·dt (→ exp(−D²·t) as dt → 0).
//
// D = 0 is allowed: the disturbance then does nothing and draws nothing.
//
// Cost per Advance: three normal draws, a square root, a division and the rotation.

#include <string>

#include "dpc/disturbance/disturbance.h"
#include "dpc/optics/rotation.h"

namespace dpc {

class RandomWalkDisturbance final : public Disturbance {
 public:
  /// `diffusion_rad_per_sqrt_s` D finite and ≥ 0; `sample_rate_hz` finite and > 0. Throws
  /// std::invalid_argument otherwise.
  RandomWalkDisturbance(double diffusion_rad_per_sqrt_s, double sample_rate_hz);

  /// Real-time. Three normal draws when D > 0, none otherwise. Time-invariant (ignores t_s).
  void Advance(double t_s, StokesVector* sop, RandomSource& random) override {
    (void)t_s;
    if (step_sigma_rad_ == 0.0) return;
    const Vector3 v = step_sigma_rad_ * Vector3(random.Normal(), random.Normal(), random.Normal());
    const double angle_squared = v.squaredNorm();
    if (!(angle_squared > 0.0)) return;
    const double angle_rad = std::sqrt(angle_squared);
    double sin_angle, cos_angle;
    SinCos(angle_rad, &sin_angle, &cos_angle);
    *sop = RotateVector(v / angle_rad, cos_angle, sin_angle, *sop);
  }

  std::string Describe() const override;

  double diffusion_rad_per_sqrt_s() const { return diffusion_rad_per_sqrt_s_; }
  /// D·√dt: the standard deviation of each component of v.
  double step_sigma_rad() const { return step_sigma_rad_; }

 private:
  double diffusion_rad_per_sqrt_s_;
  double step_sigma_rad_;
};

}  // namespace dpc
