#pragma once
// A rotation of the input SOP about a fixed axis at a constant rate (a deterministic
// scrambler, or a fibre under a steady twist rate).
//
// Per sample (dt = 1/fs): S ← Rot(r, ω·dt) · S, with Rot of paper eq. 1 precomputed at
// construction; after N samples S = Rot(r, ω·dt·N) · S(0).

#include <string>

#include "dpc/disturbance/disturbance.h"

namespace dpc {

class ConstantRotationDisturbance final : public Disturbance {
 public:
  /// `rate_rad_per_s` ω finite and ≥ 0 (reverse the axis for the opposite sense); `axis`
  /// finite and non-zero (it is normalized); `sample_rate_hz` finite and > 0. Throws
  /// std::invalid_argument otherwise.
  ConstantRotationDisturbance(double rate_rad_per_s, const Vector3& axis, double sample_rate_hz);

  /// Real-time. S ← Rot(r, ω·dt)·S. Draws nothing; ignores t_s.
  void Advance(double t_s, StokesVector* sop, RandomSource& random) override {
    (void)t_s;
    (void)random;
    *sop = step_rotation_ * (*sop);
  }

  std::string Describe() const override;

  double rate_rad_per_s() const { return rate_rad_per_s_; }
  const Vector3& axis() const { return axis_; }

 private:
  double rate_rad_per_s_;
  Vector3 axis_;
  Matrix3 step_rotation_;  ///< Rot(r, ω·dt)
};

}  // namespace dpc
