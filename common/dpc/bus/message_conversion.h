#pragma once
// Between the bus's messages (idl/dpc/bench.idl) and the core's plain structs, and the checks
// every service applies to what arrives: a message that fails a check is counted, reported by
// its reason, and never applied.

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/msg/bench.h"
#include "dpc/optics/stokes.h"

namespace dpc::bus {

/// A measured Stokes vector must be finite and of unit length to within this.
inline constexpr double kUnitStokesTolerance = 1e-6;

/// Empty if `s` is a finite unit Stokes vector; else why not, naming `field`.
std::string CheckUnitStokes(const std::array<double, 3>& s, const char* field);

/// Empty if the sample is usable: finite unit S_in and S_out, positive sequence number, finite
/// non-negative optical power if known.
std::string CheckStokesSample(const msg::StokesSample& sample);

/// Empty if the command fits a device of `control_count` controls: one finite φ per control
/// (no more than msg::MAX_CONTROLS), phi_rate_per_s empty or one finite value per control, a
/// controller id. Ranges and slew are the driver's business (it clamps and reports), not a
/// reason to refuse.
std::string CheckCommandShape(const msg::WaveplateCommand& command, int control_count);

/// The waveplates' motion a driver's state describes, in bench time (WaveplateState):
/// φ(t) = phi + rate_per_s·(min(max(t, start_ns), end_ns) − start_ns).
struct AppliedTrajectory {
  ControlVector phi;          ///< at start_ns
  ControlVector rate_per_s;   ///< per second of bench time; zero: φ holds
  int64_t start_ns = 0;
  int64_t end_ns = 0;
  bool moving = false;        ///< a non-zero rate over a non-empty interval

  /// Real-time. φ at bench time t_ns into `out` (no allocation once `out` has the size).
  void At(int64_t t_ns, ControlVector* out) const {
    *out = phi;
    if (moving) {
      const int64_t t = std::min(std::max(t_ns, start_ns), end_ns);
      *out += rate_per_s * (static_cast<double>(t - start_ns) * 1e-9);
    }
  }
};

/// The longest ramp a driver describes (its --max-ramp-s is at most 1 s).
inline constexpr uint64_t kMaxRampNs = 1'000'000'000;

/// Empty if the state fits a device of `control_count` controls: one finite phi_applied per
/// control, phi_rate_per_s empty or one finite value per control, a known mode, a ramp from
/// ramp_start_time_ns to ramp_end_time_ns of at most kMaxRampNs.
std::string CheckStateShape(const msg::WaveplateState& state, int control_count);

/// Real-time. The motion of a state that passed CheckStateShape, into `out` (its vectors sized
/// for the device are reused: nothing allocates).
void ReadTrajectory(const msg::WaveplateState& state, AppliedTrajectory* out);

/// The device's stages as the driver describes them.
/// `max_ramp_s` > 0: the driver follows commands' rates for that long (0: it does not ramp).
msg::DeviceDescription DescribeDevice(const std::vector<StageConfig>& stages,
                                      const std::string& bench_id, const std::string& driver_id,
                                      double max_slew_per_s, double max_ramp_s = 0.0);

/// The stages of a description, checked with the scenario rules (ValidateDeviceStages).
/// Throws ScenarioError (field path "device.stages[i]…") or std::invalid_argument for values
/// the IDL allows but the core does not (an unknown enum value).
std::vector<StageConfig> StagesFromDescription(const msg::DeviceDescription& description);

msg::Target TargetMessage(const TargetConfig& target, const std::string& bench_id,
                          uint64_t revision, const std::string& request_id);
/// Throws ScenarioError if the target is invalid (ValidateTargetConfig).
TargetConfig TargetFromMessage(const msg::Target& message);
TargetConfig TargetFromRequest(const msg::TargetRequest& request);

inline StokesVector ToStokes(const std::array<double, 3>& s) { return StokesVector(s[0], s[1], s[2]); }
inline std::array<double, 3> ToArray(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace dpc::bus
