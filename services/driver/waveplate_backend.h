#pragma once
// Where the driver's validated commands go: the simulated device (below) or a real one
// (line_waveplates.h: an electronic polarization controller over a serial port or TCP). A lab's
// own device (a DAC card, a piezo controller, a motor stage) implements the same interface.
//
// A command is a motion, not only a point: φ at the ramp's start plus a rate in bench time,
// for a bounded interval (WaveplateMotion). A backend with its own update clock (a DAC
// written every few µs) follows the ramp; one that cannot ramp applies the point and reports
// a zero rate in Applied(), and the state then says the waveplates hold.

#include <string>

#include "device_record.h"
#include "dpc/bench/waveplate_motion.h"

namespace dpc::services {

/// What the device can do at most, whatever it is told: finite bounds that a scenario or the
/// driver's options may narrow, never remove.
struct DeviceLimits {
  double max_abs_phi = 100.0;        ///< every control stays in [−max_abs_phi, max_abs_phi]
  double max_slew_per_s = 1e5;       ///< |dφ/dt| of every control, φ units per second
};

class WaveplateBackend {
 public:
  virtual ~WaveplateBackend() = default;
  /// The device's own bounds (finite, positive).
  virtual DeviceLimits limits() const = 0;
  /// Drives the waveplates along `motion` (already inside the ranges and slew limits). Returns
  /// an empty string on success, else what went wrong (the driver then holds and reports it).
  virtual std::string Apply(const WaveplateMotion& motion) = 0;
  /// What the device reports it is doing (the simulated device: exactly the last Apply).
  virtual const WaveplateMotion& Applied() const = 0;
  virtual std::string name() const = 0;
  /// Whether the device follows a motion's rate (else it holds each point: the driver then
  /// describes no ramps, and controllers compensate the latency instead).
  virtual bool ramps() const { return true; }
  /// Why the device cannot be driven now (disconnected, not answering, answering garbage);
  /// empty while it can. The driver holds while this is set and says why in its state.
  virtual std::string fault() const { return {}; }
};

/// The simulated device: applies instantly and exactly, within its limits (by default ±100 φ
/// units and 1e5 φ units per second: far beyond what a control law asks of it, finite so that no
/// command can drive it to absurd values). The optics (S_out from φ) are simulated by the
/// polarimeter service from the state the driver publishes, which carries the motion.
class SimulatedWaveplates final : public WaveplateBackend {
 public:
  /// `record`: where every motion is also written (DeviceRecord), so that a driver started
  /// later finds the waveplates where this one left them; may be null.
  explicit SimulatedWaveplates(const ControlVector& initial_phi, DeviceLimits limits = {},
                               DeviceRecord* record = nullptr)
      : limits_(limits), motion_(WaveplateMotion::Still(initial_phi)), record_(record) {
    if (record_ != nullptr) record_->Write(motion_);
  }
  DeviceLimits limits() const override { return limits_; }
  std::string Apply(const WaveplateMotion& motion) override {
    motion_ = motion;
    if (record_ != nullptr) record_->Write(motion_);
    return {};
  }
  const WaveplateMotion& Applied() const override { return motion_; }
  std::string name() const override { return "simulated"; }

 private:
  DeviceLimits limits_;
  WaveplateMotion motion_;
  DeviceRecord* record_;
};

}  // namespace dpc::services
