#pragma once
// What one run of ClosedLoopSimulator needs besides its loop: the input SOP, the two
// polarimeters, the statistics, the observer (trace decimation and progress) and the result.
// The general loop and the fast path share it.

#include <chrono>
#include <cstdint>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/input_sop_generator.h"
#include "dpc/disturbance/polarimeter_noise.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/run_statistics.h"

namespace dpc {

class SimulationRun {
 public:
  /// Random streams: the input uses 1, the polarimeters 2 and 3 (independent noise).
  static constexpr uint64_t kInputPolarimeterStream = 2;
  static constexpr uint64_t kOutputPolarimeterStream = 3;

  SimulationRun(const ScenarioConfig& scenario, const Target& target, int control_count,
                int64_t total_samples, SimulationObserver* observer, int64_t decimation);

  InputSopGenerator input;
  PolarimeterNoise input_polarimeter;
  PolarimeterNoise output_polarimeter;
  RunStatistics statistics;

  /// Real-time. Whether the observer gets this sample (every decimation-th, if it wants any).
  bool TakesSample() {
    if (sample_observer_ == nullptr || --until_sample_ >= 0) return false;
    until_sample_ = decimation_ - 1;
    return true;
  }
  SimulationObserver& observer() { return *observer_; }

  /// After a block ending at `done` samples: progress to the observer. False to stop the run.
  bool EndBlock(int64_t done);

  /// The result after `done` samples (the statistics' summary, speed, the final command).
  SimulationResult Finish(int64_t done, int64_t resets, const ControlVector& final_phi);

 private:
  SimulationObserver* observer_;
  SimulationObserver* sample_observer_;
  int64_t decimation_;
  int64_t until_sample_ = 0;
  int64_t total_samples_;
  int64_t next_progress_ = ClosedLoopSimulator::kProgressInterval;
  bool stopped_early_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace dpc
