#pragma once
// The bench's messages as plain structs: what the polarimeter, the controllers and the waveplate
// driver exchange, without any transport (idl/dpc/bench.idl is their wire form, field for
// field). The services' cores take and return these; the bus library (dpc/bus) converts them
// to and from the DDS types at the edge of each service and checks every field of what arrives
// there, once: a core only ever sees well-formed values (finite, unit Stokes vectors, one value
// per control, known enumerations).
//
// Units are in the names: *_ns nanoseconds (sample_time_ns: the bench's clock; *publish_time_ns
// and *receive_time_ns: wall clock), φ dimensionless control values.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/bench/waveplate_motion.h"
#include "dpc/config/scenario_config.h"
#include "dpc/optics/stokes.h"

namespace dpc {

/// One polarimeter reading (StokesSample).
struct BenchSample {
  uint64_t sequence = 0;          ///< 1, 2, 3, … per bench run
  int64_t time_ns = 0;            ///< bench clock
  int64_t publish_time_ns = 0;    ///< wall clock at publication
  StokesVector s_in = StokesVector::UnitX();   ///< unit
  StokesVector s_out = StokesVector::UnitX();  ///< unit
  std::optional<double> optical_power_w;       ///< finite, ≥ 0 when known
  bool lockstep = false;          ///< the bench waits for the state that answers this sample
};

/// A controller's command (WaveplateCommand): φ at the answered sample's time, and optionally
/// the rate along which the driver ramps it.
struct ControllerCommand {
  std::string controller_id;      ///< 1 to 63 characters
  int32_t priority = 0;           ///< larger wins
  uint64_t sequence = 0;          ///< the controller's own counter
  uint64_t answers_sample = 0;    ///< BenchSample::sequence this command answers
  int64_t sample_time_ns = 0;     ///< that sample's bench time
  int64_t sample_publish_time_ns = 0;
  int64_t publish_time_ns = 0;
  ControlVector phi;              ///< finite, one per control
  ControlVector rate_per_s;       ///< empty (φ holds) or finite, one per control
};

enum class DriverMode { kActive, kHolding };

/// What the waveplates do now (WaveplateState).
struct DriverState {
  uint64_t sequence = 0;
  uint64_t answers_sample = 0;    ///< the sample the applied command answered (0: none)
  int64_t sample_time_ns = 0;
  int64_t sample_publish_time_ns = 0;
  int64_t command_receive_time_ns = 0;
  int64_t publish_time_ns = 0;
  WaveplateMotion motion;         ///< its ramp at most kMaxStateRampNs long
  std::array<bool, kMaxControls> saturated{};  ///< per control: clamped or slew-limited
  DriverMode mode = DriverMode::kHolding;
  std::string reason;
  std::string obeyed_controller_id;  ///< empty while holding with no controller
  int32_t obeyed_priority = 0;
  uint64_t commands_applied = 0;
  uint64_t commands_rejected = 0;
  uint64_t commands_limited = 0;
  uint64_t controller_switches = 0;
  std::string last_rejection;
  /// Whose command `motion` came from: the obeyed controller's, or a standby's standing in for
  /// a sample the obeyed one had not answered in time ("" before any).
  std::string applied_controller_id;
  uint64_t stand_ins = 0;         ///< standby answers applied in place of a late one

  int control_count() const { return static_cast<int>(motion.phi.size()); }
  bool any_saturated() const {
    for (int i = 0; i < control_count(); ++i) {
      if (saturated[static_cast<size_t>(i)]) return true;
    }
    return false;
  }
};

/// The longest ramp a driver describes (its --max-ramp-s is at most 1 s).
inline constexpr uint64_t kMaxStateRampNs = 1'000'000'000;

/// The device as the driver describes it (DeviceDescription).
struct DeviceDescription {
  std::string driver_id;
  std::vector<StageConfig> stages;   ///< valid (ValidateDeviceStages)
  double max_slew_per_s = 0.0;       ///< φ units per second
  double max_ramp_s = 0.0;           ///< longest motion of a command's rate; 0: no ramps
};

/// The target and its revision (Target).
struct BenchTarget {
  uint64_t revision = 0;             ///< grows with every accepted change: epoch << 32 | count
  std::string request_id;            ///< the request that set it (empty: the scenario)
  TargetConfig target;               ///< valid (ValidateTargetConfig)
};

/// The parts of a target revision: the driver's epoch (its start, wall-clock seconds) and the
/// count of targets within it (1 = the scenario's).
inline uint32_t RevisionEpoch(uint64_t revision) { return static_cast<uint32_t>(revision >> 32); }
inline uint32_t RevisionCount(uint64_t revision) { return static_cast<uint32_t>(revision); }


/// A controller's health and the law's diagnostics (ControllerStatus).
struct ControllerStatusReport {
  std::string controller_id;
  int32_t priority = 0;
  std::string law;
  bool obeyed = false;
  std::string condition;
  uint64_t answers_sample = 0;
  double error_deg = 0.0;
  double sigma_max = 0.0;
  double sigma_min = 0.0;
  double nullspace_active_fraction = 0.0;
  double compute_time_mean_s = 0.0;
  double compute_time_max_s = 0.0;
  uint64_t updates = 0;
  uint64_t failed_updates = 0;
  uint64_t rejected_samples = 0;
  uint64_t missed_deadlines = 0;
  std::string last_rejection;
  int64_t publish_time_ns = 0;
};

}  // namespace dpc
