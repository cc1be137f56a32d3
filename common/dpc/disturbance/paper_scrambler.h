#pragma once
// The paper's polarization scrambler (section IV): the input SOP rotates about S3 at a constant
// 100 krad/s, "perturbed by the rotation about the axis S2 with randomly distributed angles".
//
// Per sample (dt = 1/fs), first the constant rotation, then the kick:
//
//   S ← Rot(k, δ) · Rot(r, ω·dt) · S,      δ ~ N(0, σ²),  σ = kick_rms_ratio · ω · dt
//
// r: the rotation axis (paper: S3), k: the kick axis (paper: S2), ω: the rate in rad/s, Rot
// the rotation of paper eq. 1. The draws δ are independent between samples.
//
// The paper gives no distribution for the kicks. We use a Gaussian kick per sample with, by
// default, σ = ω·dt (kick_rms_ratio = 1): as large in RMS as the deterministic step. The kicks
// form a random walk about k: after N samples their sum has RMS σ√N (at 50 MHz and 100 krad/s,
// σ = 2 mrad per sample and σ√D ≈ 14 mrad over the 1 µs loop delay, D = 50 samples). Near the
// S1–S2 equator that the rotation about S3 sweeps, a rotation about S2 by an angle a moves S by
// a·|cos α| (α the SOP's longitude), whose mean over the orbit is 2/π ≈ 0.64: the kicks
// accumulated over D samples move the SOP by ≈ 0.63·σ·√D on the sphere (RMS over the kicks,
// averaged over the orbit; ≈ 9 mrad for the paper's numbers), against ω·dt·D = 0.1 rad of
// deterministic rotation.
//
// The disturbance is time-invariant (Advance ignores t_s). With kick_rms_ratio = 0 it draws
// nothing and is the constant rotation alone.

#include <string>

#include "dpc/disturbance/disturbance.h"
#include "dpc/optics/rotation.h"

namespace dpc {

class PaperScrambler final : public Disturbance {
 public:
  /// `rate_rad_per_s` ω ≥ 0 and `kick_rms_ratio` ≥ 0, both finite; the axes need not be unit
  /// (they are normalized) but must be finite and non-zero; `sample_rate_hz` finite and > 0.
  /// Throws std::invalid_argument otherwise. For the opposite sense of rotation reverse the
  /// axis. Precomputes Rot(r, ω·dt).
  PaperScrambler(double rate_rad_per_s, double kick_rms_ratio, const Vector3& rotation_axis,
                 const Vector3& kick_axis, double sample_rate_hz);

  /// Real-time. S ← Rot(k, δ)·Rot(r, ω·dt)·S; one normal draw when σ > 0, none otherwise.
  [[gnu::always_inline]] void Advance(double t_s, StokesVector* sop,
                                      RandomSource& random) override {
    (void)t_s;
    double x = (*sop)[0], y = (*sop)[1], z = (*sop)[2];
    if (rotation_elemental_ != ElementalAxis::kGeneral) {  // the paper's S3: a plane rotation
      RotateElemental(rotation_elemental_, step_cos_, step_sin_, x, y, z);
    } else {
      const Vector3 r = step_rotation_ * Vector3(x, y, z);
      x = r[0], y = r[1], z = r[2];
    }
    if (kick_sigma_rad_ > 0.0) {
      double sin_kick, cos_kick;
      SinCos(kick_sigma_rad_ * random.Normal(), &sin_kick, &cos_kick);
      if (kick_elemental_ != ElementalAxis::kGeneral) {  // the paper's S2
        RotateElemental(kick_elemental_, cos_kick, sin_kick, x, y, z);
      } else {
        const Vector3 r = RotateVector(kick_axis_, cos_kick, sin_kick, Vector3(x, y, z));
        x = r[0], y = r[1], z = r[2];
      }
    }
    *sop = StokesVector(x, y, z);
  }

  std::string Describe() const override;

  double rate_rad_per_s() const { return rate_rad_per_s_; }
  /// σ = kick_rms_ratio·ω·dt, the RMS kick per sample.
  double kick_sigma_rad() const { return kick_sigma_rad_; }
  const Vector3& rotation_axis() const { return rotation_axis_; }
  const Vector3& kick_axis() const { return kick_axis_; }
  /// What Advance computes with (the batched simulator repeats it in vector lanes): each axis
  /// as an elemental one (kGeneral if it is not S1, S2 or S3) and the step's cos and sin.
  ElementalAxis rotation_elemental() const { return rotation_elemental_; }
  ElementalAxis kick_elemental() const { return kick_elemental_; }
  double step_cos() const { return step_cos_; }
  double step_sin() const { return step_sin_; }

 private:
  double rate_rad_per_s_;
  double kick_rms_ratio_;
  Vector3 rotation_axis_;
  Vector3 kick_axis_;
  double sample_period_s_;
  double kick_sigma_rad_;
  Matrix3 step_rotation_;  ///< Rot(r, ω·dt)
  double step_cos_ = 1.0, step_sin_ = 0.0;
  ElementalAxis rotation_elemental_ = ElementalAxis::kGeneral;
  ElementalAxis kick_elemental_ = ElementalAxis::kGeneral;
};

}  // namespace dpc
