#pragma once
// Between the bus's messages (idl/dpc/bench.idl) and the core's plain structs, and the checks
// every service applies to what arrives: a message that fails a check is counted, reported by
// its reason, and never applied.

#include <array>
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
/// (no more than msg::MAX_CONTROLS), a controller id. Ranges and slew are the driver's
/// business (it clamps and reports), not a reason to refuse.
std::string CheckCommandShape(const msg::WaveplateCommand& command, int control_count);

/// The device's stages as the driver describes them.
msg::DeviceDescription DescribeDevice(const std::vector<StageConfig>& stages,
                                      const std::string& bench_id, const std::string& driver_id,
                                      double max_slew_per_s);

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
