#include "dpc/sim/closed_loop_simulator.h"

#include <chrono>
#include <cmath>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Seeds of the two polarimeters' noise streams, distinct from the input's.
constexpr uint64_t kInputPolarimeterStream = 2;
constexpr uint64_t kOutputPolarimeterStream = 3;

}  // namespace

ClosedLoopSimulator::ClosedLoopSimulator(const ScenarioConfig& scenario,
                                         ControlLawFactory law_factory)
    : scenario_(scenario), law_factory_(law_factory ? std::move(law_factory) : MakeControlLaw) {
  ValidateScenario(scenario_);
  chain_ = std::make_unique<WaveplateChain>(BuildChain(scenario_.stages));
  target_ = std::make_unique<Target>(BuildTarget(scenario_.target));
  law_config_ = BuildControlLawConfig(scenario_.controller, scenario_.simulation);
  initial_phi_ = BuildInitialPhi(scenario_.controller, chain_->control_count());
  delay_samples_ = DelaySamples(scenario_.simulation);
  total_samples_ = TotalSamples(scenario_.simulation);
  const double activation = scenario_.controller.activation_s * scenario_.simulation.sample_rate_hz;
  activation_sample_ = static_cast<int64_t>(std::ceil(activation - 1e-9 * std::max(1.0, activation)));
  // Fail here, not in Run, if the law does not fit the device.
  law_factory_(law_config_, chain_->control_count(), target_->is_point());
}

ClosedLoopSimulator::~ClosedLoopSimulator() = default;

SimulationResult ClosedLoopSimulator::Run(SimulationObserver* observer, int64_t decimation) {
  const SimulationConfig& sim = scenario_.simulation;
  const double dt_s = 1.0 / sim.sample_rate_hz;
  const WaveplateChain& chain = *chain_;
  const Target& target = *target_;
  if (decimation < 1) decimation = 1;

  InputSopGenerator input = MakeInputSopGenerator(scenario_.input, sim.seed, sim.sample_rate_hz);
  PolarimeterNoise input_polarimeter(sim.polarimeter_noise_deg, sim.seed,
                                     kInputPolarimeterStream);
  PolarimeterNoise output_polarimeter(sim.polarimeter_noise_deg, sim.seed,
                                      kOutputPolarimeterStream);
  std::unique_ptr<ControlLaw> law =
      law_factory_(law_config_, chain.control_count(), target.is_point());
  ControlIntegrator integrator(chain, initial_phi_);
  RunStatistics statistics(chain.control_count(), scenario_.controller.activation_s,
                           sim.lock_threshold_deg, sim.statistics_start_s);

  // The delay line: slot k mod D holds the command issued at sample k − D, as a pose.
  const int64_t delay = delay_samples_;
  std::vector<ChainPose> line(static_cast<size_t>(delay));
  std::vector<uint64_t> line_version(static_cast<size_t>(delay), 0);
  chain.ComputePose(integrator.phi(), &line[0]);
  for (auto& pose : line) pose = line[0];
  uint64_t version = 0;          // of the controller's latest command
  int64_t latest = delay - 1;    // slot holding the latest command

  ControlProblem problem;
  problem.chain = &chain;
  problem.target = &target;
  problem.loop_mode = scenario_.controller.loop;
  ControlVector delta_phi;

  SimulationResult result;
  const auto start = std::chrono::steady_clock::now();
  int64_t slot = 0;
  int64_t until_trace = 0;
  int64_t k = 0;
  for (; k < total_samples_; ++k) {
    const double t_s = static_cast<double>(k) * dt_s;
    const StokesVector& s_in = input.Next();
    const ChainPose& applied = line[static_cast<size_t>(slot)];
    const StokesVector s_out = chain.Output(applied, s_in);
    const double error_rad = target.DistanceRad(s_out);
    const bool active = k >= activation_sample_;
    if (active) {
      statistics.AddSample(t_s, error_rad, target.LeakFraction(s_out), applied.phi);
    }
    if (observer != nullptr && --until_trace < 0) {
      observer->OnSample(SampleView{k, t_s, s_in, s_out, applied.phi, error_rad * kRadToDeg});
      until_trace = decimation - 1;
    }

    bool issued = false;
    if (active) {
      if (k == activation_sample_) law->Activate(integrator.phi());
      problem.pose = &line[static_cast<size_t>(latest)];
      problem.s_in = input_polarimeter.Measure(s_in);
      problem.s_out_measured = output_polarimeter.Measure(s_out);
      UpdateControlProblem(&problem);
      const ControlStatus status = law->ComputeUpdate(problem, &delta_phi);
      const ControlIntegrator::Outcome outcome = integrator.Apply(status, delta_phi);
      const ControlDiagnostics& diagnostics = law->diagnostics();
      statistics.AddUpdate(diagnostics.nullspace_active, !IsUsable(status),
                           status == ControlStatus::kRankDeficient,
                           outcome == ControlIntegrator::Outcome::kClamped, diagnostics.sigma_min);
      if (outcome != ControlIntegrator::Outcome::kRejected) {
        ++version;
        chain.ComputePose(integrator.phi(), &line[static_cast<size_t>(slot)]);
        line_version[static_cast<size_t>(slot)] = version;
        issued = true;
      }
    }
    if (!issued && line_version[static_cast<size_t>(slot)] != version) {
      line[static_cast<size_t>(slot)] = line[static_cast<size_t>(latest)];
      line_version[static_cast<size_t>(slot)] = version;
    }
    latest = slot;
    if (++slot == delay) slot = 0;

    if (observer != nullptr && ((k + 1) & (kProgressInterval - 1)) == 0 &&
        !observer->OnProgress(k + 1, total_samples_)) {
      ++k;
      result.stopped_early = true;
      break;
    }
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (observer != nullptr && !result.stopped_early) observer->OnProgress(k, total_samples_);

  result.summary = statistics.Summarize(k, law->diagnostics().resets);
  result.wall_time_s = wall_s;
  result.samples_per_s = wall_s > 0.0 ? static_cast<double>(k) / wall_s : 0.0;
  result.final_phi = integrator.phi();
  return result;
}

}  // namespace dpc
