#pragma once
// The report of one closed-loop run, as `dpc sim` prints it (text, or one JSON object with
// --json; README "dpc sim output" lists every field) and as the polarimeter service writes it
// for a bench run. NaN and unset values are written as null.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/sweep_runner.h"

namespace dpc::cli {

/// What identifies a run besides its results.
struct RunDescription {
  ScenarioConfig scenario;      ///< validated, as run
  std::string device;           ///< WaveplateChain::Describe()
  int controls = 0;
  std::string target;           ///< Target::Describe()
  int64_t delay_samples = 0;    ///< the loop delay in samples
  std::string loop_kernel;      ///< "fast" or "general" (the simulator), "bench" (the services)
};

/// The simulator's run.
RunDescription DescribeRun(const ClosedLoopSimulator& simulator);
/// A run of `scenario` (validated) on `chain` and `target` by `loop_kernel`.
RunDescription DescribeRun(const ScenarioConfig& scenario, const WaveplateChain& chain, const Target& target,
                           std::string loop_kernel);

/// The settings that identify a run (scenario name, device, law, rates, timing, seed).
nlohmann::ordered_json RunSettingsJson(const RunDescription& run);

/// Settings + results (+ warnings) of one run.
nlohmann::ordered_json RunReportJson(const RunDescription& run, const SimulationResult& result,
                                     const std::vector<std::string>& warnings);

/// The input rotation rate of the first paper scrambler or constant rotation, or NaN.
double InputRateRadPerS(const ScenarioConfig& scenario);

/// A human-readable multi-line summary (the default output of `dpc sim`).
std::string RunReportText(const RunDescription& run, const SimulationResult& result);

/// How fast a sweep ran (RunSweep with `threads`, in `wall_s`): "12 runs, 6.0e+06 samples in
/// 0.21 s: 28.6 M samples/s on 2 threads, in avx512 batches of up to 8 runs".
std::string DescribeSweepSpeed(const std::vector<SweepOutcome>& outcomes, int threads, double wall_s);

}  // namespace dpc::cli
