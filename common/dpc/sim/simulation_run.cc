#include "dpc/sim/simulation_run.h"

namespace dpc {

SimulationRun::SimulationRun(const ScenarioConfig& scenario, const Target& target,
                             int control_count, int64_t total_samples,
                             SimulationObserver* observer, int64_t decimation)
    : input(MakeInputSopGenerator(scenario.input, scenario.simulation.seed,
                                  scenario.simulation.sample_rate_hz)),
      input_polarimeter(scenario.simulation.polarimeter_noise_deg, scenario.simulation.seed,
                        kInputPolarimeterStream),
      output_polarimeter(scenario.simulation.polarimeter_noise_deg, scenario.simulation.seed,
                         kOutputPolarimeterStream),
      statistics(target, control_count, scenario.controller.activation_s,
                 scenario.simulation.lock_threshold_deg, scenario.simulation.statistics_start_s,
                 // A hair under settle·dt, so the window opens on that very sample.
                 (static_cast<double>(scenario.simulation.settle_samples) - 0.5) /
                     scenario.simulation.sample_rate_hz),
      observer_(observer),
      sample_observer_(observer != nullptr && observer->wants_samples() ? observer : nullptr),
      decimation_(decimation < 1 ? 1 : decimation),
      total_samples_(total_samples),
      start_(std::chrono::steady_clock::now()) {}

bool SimulationRun::EndBlock(int64_t done) {
  if (observer_ == nullptr || done < next_progress_) return true;
  next_progress_ += ClosedLoopSimulator::kProgressInterval;
  stopped_early_ = !observer_->OnProgress(done, total_samples_);
  return !stopped_early_;
}

SimulationResult SimulationRun::Finish(int64_t done, int64_t resets,
                                       const ControlVector& final_phi) {
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (observer_ != nullptr && !stopped_early_) observer_->OnProgress(done, total_samples_);
  SimulationResult result;
  result.summary = statistics.Summarize(done, resets);
  result.wall_time_s = wall_s;
  result.samples_per_s = wall_s > 0.0 ? static_cast<double>(done) / wall_s : 0.0;
  result.stopped_early = stopped_early_;
  result.final_phi = final_phi;
  return result;
}

}  // namespace dpc
