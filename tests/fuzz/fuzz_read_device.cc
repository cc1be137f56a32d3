// ReadDevice (bus/message_conversion.h) on any DeviceDescription payload a peer can send.
#include <cmath>
#include <cstdint>
#include <exception>
#include <stdexcept>

#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "fuzz_wire.h"

namespace {

bool FiniteMap(const dpc::ControlMapConfig& map) {
  switch (map.kind) {
    case dpc::ControlMapConfig::Kind::kLinear:
      return std::isfinite(map.rad_per_unit) && map.rad_per_unit != 0.0 && std::isfinite(map.offset_rad);
    case dpc::ControlMapConfig::Kind::kPolynomial: return dpc::fuzz::AllFinite(map.coefficients_rad);
    case dpc::ControlMapConfig::Kind::kTable:
      return dpc::fuzz::AllFinite(map.table_control) && dpc::fuzz::AllFinite(map.table_angle_rad);
    case dpc::ControlMapConfig::Kind::kTablesByCondition:
      return false;  // never read from the wire: a device sends the table resolved at its operating point
  }
  return false;
}

bool MapWithinIdl(const dpc::ControlMapConfig& map) {
  return map.coefficients_rad.size() <= dpc::msg::MAX_MAP_POINTS &&
         map.table_control.size() <= dpc::msg::MAX_MAP_POINTS &&
         map.table_angle_rad.size() <= dpc::msg::MAX_MAP_POINTS;
}

bool FiniteRange(const std::optional<dpc::ControlRange>& range) {
  return !range || (std::isfinite(range->min) && std::isfinite(range->max) && range->min < range->max);
}

bool FiniteAngle(const dpc::StageAngleConfig& angle) {
  return angle.controlled ? FiniteMap(angle.map) && FiniteRange(angle.range) : std::isfinite(angle.fixed_rad);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::DeviceDescription message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  DeviceDescription out;
  if (!bus::ReadDevice(message, &out).empty()) return 0;

  // Accepted: stages that pass the scenario rules, known enumerations, a finite slew and ramp.
  DPC_FUZZ_CHECK(!out.stages.empty() && out.stages.size() <= static_cast<size_t>(kMaxStages), "out-of-range",
                 "accepted %zu stages", out.stages.size());
  const int controls = ScenarioControlCount(out.stages);
  DPC_FUZZ_CHECK(controls >= 1 && controls <= kMaxControls, "out-of-range", "accepted %d controls", controls);
  DPC_FUZZ_CHECK(out.stages.size() <= msg::MAX_STAGES && controls <= static_cast<int>(msg::MAX_CONTROLS),
                 "idl-bound",
                 "accepted a device of %zu stages and %d controls: its commands and states cannot carry "
                 "them (MAX_STAGES %u, MAX_CONTROLS %u; ReadCommand refuses more than MAX_CONTROLS φ)",
                 out.stages.size(), controls, msg::MAX_STAGES, msg::MAX_CONTROLS);
  DPC_FUZZ_CHECK(std::isfinite(out.max_slew_per_s) && std::isfinite(out.max_ramp_s), "non-finite",
                 "accepted slew %g, ramp %g", out.max_slew_per_s, out.max_ramp_s);
  DPC_FUZZ_CHECK(out.max_slew_per_s >= 0.0 && out.max_ramp_s >= 0.0, "out-of-range", "accepted slew %g, ramp %g",
                 out.max_slew_per_s, out.max_ramp_s);
  DPC_FUZZ_CHECK(out.driver_id.size() <= 64, "idl-bound", "driver_id of %zu characters", out.driver_id.size());
  for (size_t i = 0; i < out.stages.size(); ++i) {
    const StageConfig& stage = out.stages[i];
    DPC_FUZZ_CHECK(stage.kind == StageConfig::Kind::kFixedAxis || stage.kind == StageConfig::Kind::kAdjustableAxis,
                   "out-of-range", "stages[%zu] kind %d", i, static_cast<int>(stage.kind));
    DPC_FUZZ_CHECK(stage.name.size() <= 32, "idl-bound", "stages[%zu].name of %zu characters", i,
                   stage.name.size());
    if (stage.kind == StageConfig::Kind::kFixedAxis) {
      DPC_FUZZ_CHECK(fuzz::AllFiniteVector(stage.axis) && stage.axis.norm() >= kMinAxisLength, "non-finite",
                     "stages[%zu] axis [%g, %g, %g]", i, stage.axis.x(), stage.axis.y(), stage.axis.z());
      DPC_FUZZ_CHECK(FiniteMap(stage.map) && FiniteRange(stage.range), "non-finite",
                     "stages[%zu] map or range not finite", i);
      DPC_FUZZ_CHECK(MapWithinIdl(stage.map), "idl-bound", "stages[%zu] map of more than %u points", i,
                     msg::MAX_MAP_POINTS);
    } else {
      DPC_FUZZ_CHECK(stage.retardance.controlled || stage.orientation.controlled, "out-of-range",
                     "stages[%zu] adjustable with no control", i);
      DPC_FUZZ_CHECK(FiniteAngle(stage.retardance) && FiniteAngle(stage.orientation), "non-finite",
                     "stages[%zu] angle not finite", i);
      DPC_FUZZ_CHECK(MapWithinIdl(stage.retardance.map) && MapWithinIdl(stage.orientation.map), "idl-bound",
                     "stages[%zu] map of more than %u points", i, msg::MAX_MAP_POINTS);
    }
  }
  // A controller configures itself from it: the chain must build, with the controls counted.
  try {
    const WaveplateChain chain = BuildChain(out.stages);
    DPC_FUZZ_CHECK(chain.control_count() == controls, "contract", "chain of %d controls, counted %d",
                   chain.control_count(), controls);
  } catch (const std::invalid_argument& e) {
    DPC_FUZZ_CHECK(false, "build", "an accepted device does not build: %s", e.what());
  }
  return 0;
}
