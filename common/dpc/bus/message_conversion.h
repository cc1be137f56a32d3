#pragma once
// Between the bus's messages (idl/dpc/bench.idl) and the core's plain structs
// (bench/bench_messages.h), and the checks every service applies to what arrives, once, at its
// edge: a message that fails a check is counted, reported by its reason, and never applied.
// The Read* functions never throw and never trust a field: sizes, numbers, enumerations.

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/bench/bench_messages.h"
#include "dpc/bench/bench_summary.h"
#include "dpc/config/scenario_config.h"
#include "dpc/msg/bench.h"
#include "dpc/optics/stokes.h"

namespace dpc::bus {

/// A measured Stokes vector must be finite and of unit length to within this.
inline constexpr double kUnitStokesTolerance = 1e-6;

/// Empty if `s` is a finite unit Stokes vector; else why not, naming `field`.
std::string CheckUnitStokes(const std::array<double, 3>& s, const char* field);

/// Reads a polarimeter sample into `out`. Empty if it is usable: a positive sequence number,
/// finite unit S_in and S_out, a finite non-negative optical power if known; else why not.
std::string ReadSample(const msg::StokesSample& message, BenchSample* out);
void WriteSample(const BenchSample& sample, const std::string& bench_id, msg::StokesSample* out);

/// Reads a command for a device of `control_count` controls into `out`. Empty if it is usable:
/// a controller id, one finite φ per control (no more than msg::MAX_CONTROLS), phi_rate_per_s
/// empty or one finite value per control; else why not (controller_id and answers_sample are
/// read even then, for the report). Ranges and slew are the driver's business (it clamps and
/// reports), not a reason to refuse.
std::string ReadCommand(const msg::WaveplateCommand& message, int control_count, ControllerCommand* out);
/// Writes `command` into `out` in place: once `out` has held a command of this size, nothing
/// is allocated.
void WriteCommand(const ControllerCommand& command, const std::string& bench_id, msg::WaveplateCommand* out);

/// Reads a driver's state for a device of `control_count` controls into `out` (its strings and
/// vectors reused: nothing is allocated once they have their size). Empty if it is usable: one
/// finite phi_applied per control, phi_rate_per_s empty or one finite value per control, a known
/// mode, a ramp from ramp_start_time_ns to ramp_end_time_ns of at most kMaxStateRampNs; else why
/// not.
std::string ReadState(const msg::WaveplateState& message, int control_count, DriverState* out);
void WriteState(const DriverState& state, const std::string& bench_id, msg::WaveplateState* out);

/// The device's description as the driver publishes it.
msg::DeviceDescription DeviceMessage(const DeviceDescription& device, const std::string& bench_id);
/// Reads a description into `out`: empty if its stages pass the scenario rules
/// (ValidateDeviceStages; a bad one is named by its path "device.stages[i]…") and every
/// enumeration is known; else why not.
std::string ReadDevice(const msg::DeviceDescription& message, DeviceDescription* out);

msg::Target TargetMessage(const BenchTarget& target, const std::string& bench_id);
/// Reads a target into `out`: empty if it is valid (ValidateTargetConfig); else why not.
std::string ReadTarget(const msg::Target& message, BenchTarget* out);
/// The target a request asks for. Throws ScenarioError if it is invalid (ValidateTargetConfig),
/// std::invalid_argument for an unknown kind.
TargetConfig TargetFromRequest(const msg::TargetRequest& request);

/// `text` for people: each control character (a terminal escape, a newline that would forge a
/// log line) becomes '?'. PrintableName also bounds the length.
std::string PrintableText(std::string text);

msg::ControllerStatus StatusMessage(const ControllerStatusReport& status, const std::string& bench_id);
/// Reads a controller's status into `out`: empty if it is usable (a controller id; every figure
/// finite and not negative, the error at most 180°, the null-space fraction at most 1); else
/// why not. A control character in its text (a terminal escape, a newline) becomes '?'.
std::string ReadStatus(const msg::ControllerStatus& message, ControllerStatusReport* out);

/// Writes a summary into `out` (strings cut to their bounds, the trail to its bound).
void WriteSummary(const BenchSummary& summary, const std::string& bench_id, msg::BenchSummary* out);
/// Reads a summary into `out`: empty if it is usable (finite figures, unit S_in/S_out and trail
/// points, a trail of whole points, the state's φ and saturation of one size within
/// msg::MAX_CONTROLS, a known mode); else why not.
std::string ReadSummary(const msg::BenchSummary& message, BenchSummary* out);

inline StokesVector ToStokes(const std::array<double, 3>& s) { return StokesVector(s[0], s[1], s[2]); }
inline std::array<double, 3> ToArray(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace dpc::bus
