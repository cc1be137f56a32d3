#pragma once
// Runs many independent simulations on all cores (a sweep over rates, seeds, methods, devices).
//
// Runs of the fast path's class that may share a batch (the same stage axes, delay, sample count
// and activation: seeds, rates, laws, steps, targets may differ) are simulated together in the
// lanes of a vector (batch_simulator.h: 8 with AVX-512, 4 with AVX2; DPC_BATCH_ISA=none runs
// each alone); every other scenario by its own ClosedLoopSimulator. Workers (one per thread) take
// the next batch or run from a shared counter; runs of one kind are split over at least as many
// batches as there are threads. Runs share nothing, so the results equal those of running each
// scenario alone, bit for bit (every run seeds its own random streams; the batch's lanes repeat
// the scalar loop's operations).

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

/// The worker threads RunSweep starts for `runs` runs when asked for `threads` (≤ 0: one per
/// hardware thread; never more than the runs).
int SweepThreads(int threads, size_t runs);

/// Runs every scenario; `threads` ≤ 0 means std::thread::hardware_concurrency(). `progress` (if
/// set) is called after each run finishes, serialized, with (finished, total). If `stop` becomes
/// true, runs not yet started are skipped (ok = false, error = "skipped").
std::vector<SweepOutcome> RunSweep(const std::vector<ScenarioConfig>& scenarios, int threads,
                                   const std::function<void(size_t, size_t)>& progress = {},
                                   const std::atomic<bool>* stop = nullptr);

}  // namespace dpc
