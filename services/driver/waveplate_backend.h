#pragma once
// Where the driver's validated commands go. The simulated device now; a hardware backend (a
// DAC, a piezo controller, a motor stage) implements the same interface later.

#include <string>

#include "dpc/optics/waveplate_chain.h"

namespace dpc::services {

class WaveplateBackend {
 public:
  virtual ~WaveplateBackend() = default;
  /// Drives the waveplates to `phi` (one value per control, already inside the ranges and
  /// slew limits). Returns an empty string on success, else what went wrong (the driver then
  /// holds and reports it).
  virtual std::string Apply(const ControlVector& phi) = 0;
  /// What the device reports it applied (the simulated device: exactly the last Apply).
  virtual ControlVector Applied() const = 0;
  virtual std::string name() const = 0;
};

/// The simulated device: applies instantly and exactly. The optics (S_out from φ) are simulated
/// by the polarimeter service from the state the driver publishes.
class SimulatedWaveplates final : public WaveplateBackend {
 public:
  explicit SimulatedWaveplates(ControlVector initial_phi) : phi_(std::move(initial_phi)) {}
  std::string Apply(const ControlVector& phi) override {
    phi_ = phi;
    return {};
  }
  ControlVector Applied() const override { return phi_; }
  std::string name() const override { return "simulated"; }

 private:
  ControlVector phi_;
};

}  // namespace dpc::services
