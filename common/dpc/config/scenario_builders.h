#pragma once
// Builds the core objects a scenario describes: the stage maps and the waveplate chain, the
// target, the loop timing a law needs and the initial control vector.
//
// The builders expect a scenario that passed ValidateScenario (scenario_validation.h). Given a
// bad one they never crash: the core constructors throw std::invalid_argument, and the builders
// re-throw it as a ScenarioError (also a std::invalid_argument) located at the stage, target or
// field concerned where they know it.

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/control/target.h"
#include "dpc/optics/control_map.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

/// ControlMap::Linear / Polynomial / Table from the config's kind (tables by condition as
/// ResolveConditionTables resolves them). Throws std::invalid_argument for an invalid map.
ControlMap BuildControlMap(const ControlMapConfig& config);

/// A tables_by_condition map as the plain lookup table it stands for at its operating point:
/// between the two tables around the point, the angle at every control point of either is
/// interpolated between the two tables' values there (each table read piecewise linearly,
/// extrapolated linearly beyond its ends), with the weight linear in the temperature or in
/// 1/λ; at a table's own condition, that table. Other kinds are returned as they are. Throws
/// std::invalid_argument if there are fewer than 2 tables, the point is outside their span or
/// not finite, a table is invalid, or the result has more than ControlMap::kMaxTablePoints.
ControlMapConfig ResolveConditionTables(const ControlMapConfig& config);

/// "temperature_c" or "wavelength_nm"; for messages, the unit ("°C" or "nm") and the noun
/// ("temperature" or "wavelength").
const char* ConditionKeyName(ControlMapConfig::Condition condition);
const char* ConditionUnit(ControlMapConfig::Condition condition);
const char* ConditionNoun(ControlMapConfig::Condition condition);

/// One WaveplateStage per config, in order: fixed-axis stages become WaveplateStage::FixedAxis
/// (axis normalized, map, range), adjustable-axis stages WaveplateStage::AdjustableAxis with
/// StageAngle::Fixed or StageAngle::Controlled for the retardance and the orientation. Stage
/// names are passed through. Throws ScenarioError at "stages" (count) or "stages[i]" (a stage
/// the core rejects).
WaveplateChain BuildChain(const std::vector<StageConfig>& stages);

/// Target::Point or Target::Set. Throws ScenarioError at "target.point" / "target.set" if the
/// core rejects it.
Target BuildTarget(const TargetConfig& config);

/// The loop timing a law needs (MakeControlLaw): the sample rate and the loop delay in samples
/// (DelaySamples).
LawTiming BuildLawTiming(const SimulationConfig& simulation);

/// controller.initial_phi as a ControlVector, or zeros(control_count) when it is empty. Throws
/// ScenarioError at "controller.initial_phi" if its size is not control_count, or if
/// control_count is not in [0, kMaxControls].
ControlVector BuildInitialPhi(const ControllerConfig& controller, int control_count);

}  // namespace dpc
