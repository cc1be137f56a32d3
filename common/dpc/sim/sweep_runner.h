#pragma once
// Runs many independent simulations on all cores (a sweep over rates, seeds, methods, devices).
//
// Each scenario is simulated by its own ClosedLoopSimulator on one worker thread; runs share
// nothing, so the results equal those of running each scenario alone (bit for bit: every run
// seeds its own random streams). Workers take the next scenario from a shared counter.

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/sim/closed_loop_simulator.h"

namespace dpc {

struct SweepOutcome {
  bool ok = false;
  std::string error;  ///< what() of the exception when !ok (e.g. an invalid scenario)
  SimulationResult result;
};

/// Runs every scenario; `threads` ≤ 0 means std::thread::hardware_concurrency(). `progress` (if
/// set) is called after each run finishes, serialized, with (finished, total). If `stop` becomes
/// true, runs not yet started are skipped (ok = false, error = "skipped").
std::vector<SweepOutcome> RunSweep(const std::vector<ScenarioConfig>& scenarios, int threads,
                                   const std::function<void(size_t, size_t)>& progress = {},
                                   const std::atomic<bool>* stop = nullptr);

}  // namespace dpc
