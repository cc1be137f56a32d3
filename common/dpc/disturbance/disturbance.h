#pragma once
// The one small interface of every input-SOP disturbance (the polarization scrambler of the
// paper's section IV and the other processes a fibre link shows), and the precondition checks
// its implementations share.
//
// A disturbance is a time-dependent random rotation of the Poincaré sphere applied to the input
// SOP once per sample: S ← D_t(S). Its sample period dt = 1/fs is fixed at construction. The
// call for time t covers the interval [t, t + dt) (InputSopGenerator defines the timing of a
// whole input). Randomness comes from the caller's RandomSource, so that one seed drives the
// composition of several disturbances reproducibly.
//
// Real-time contract: Advance runs once per sample. It must not allocate, lock or block.
// Constructors and Describe run outside the loop and may allocate.

#include <string>

#include "dpc/disturbance/random_source.h"
#include "dpc/optics/stokes.h"

namespace dpc {

class Disturbance {
 public:
  virtual ~Disturbance() = default;

  /// Real-time. Rotates *sop for the sample that starts at time t_s (the sample period is
  /// fixed at construction). Draws from `random` only when the disturbance is random.
  virtual void Advance(double t_s, StokesVector* sop, RandomSource& random) = 0;

  /// "constant rotation: 1e+05 rad/s about [0, 0, 1]".
  virtual std::string Describe() const = 0;
};

/// The sample period 1/fs in seconds. Throws std::invalid_argument naming `who` unless
/// `sample_rate_hz` is finite and > 0.
double SamplePeriodFromRate(double sample_rate_hz, const std::string& who);

/// `axis`/|axis|. Throws std::invalid_argument naming `what` if `axis` is not finite or has
/// length < 1e-12.
Vector3 NormalizedAxis(const Vector3& axis, const std::string& what);

/// Throws std::invalid_argument naming `what` unless `value` is finite and ≥ 0.
void RequireNonNegativeFinite(double value, const std::string& what);

}  // namespace dpc
