#pragma once
// `dpc sim --json`: one JSON object per run (see README "dpc sim output" for every field).
// NaN and unset values are written as null.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "dpc/sim/closed_loop_simulator.h"

namespace dpc::tools {

/// The settings that identify a run (scenario name, device, law, rates, timing, seed).
nlohmann::ordered_json RunSettingsJson(const ClosedLoopSimulator& simulator);

/// Settings + results (+ warnings) of one run.
nlohmann::ordered_json RunReportJson(const ClosedLoopSimulator& simulator,
                                     const SimulationResult& result,
                                     const std::vector<std::string>& warnings);

/// The input rotation rate of the first paper scrambler or constant rotation, or NaN.
double InputRateRadPerS(const ScenarioConfig& scenario);

/// A human-readable multi-line summary (the default output of `dpc sim`).
std::string RunReportText(const ClosedLoopSimulator& simulator, const SimulationResult& result);

}  // namespace dpc::tools
