#pragma once
// The controller's integrator (paper eq. 6): φ[k+1] = φ[k] + Δφ[k], kept inside each control's
// range (anti-windup: the state never leaves what the device can apply). An update from a law
// that failed (negative status) or that is not finite is never applied.

#include <cstdint>

#include "dpc/control/control_law.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

class ControlIntegrator {
 public:
  /// Throws std::invalid_argument if `initial_phi` has the wrong size or is not finite. The
  /// initial value is clamped into the ranges.
  ControlIntegrator(const WaveplateChain& chain, const ControlVector& initial_phi);

  enum class Outcome { kApplied, kClamped, kRejected };

  /// Real-time. Applies Δφ if `status` is usable and Δφ is finite with the right size.
  Outcome Apply(ControlStatus status, const ControlVector& delta_phi);

  /// Not real-time. Sets φ (clamped into the ranges). Throws like the constructor.
  void Reset(const ControlVector& phi);

  const ControlVector& phi() const { return phi_; }
  int64_t rejected() const { return rejected_; }
  int64_t clamped() const { return clamped_; }

 private:
  const WaveplateChain& chain_;
  ControlVector phi_;
  int64_t rejected_ = 0;
  int64_t clamped_ = 0;
};

}  // namespace dpc
