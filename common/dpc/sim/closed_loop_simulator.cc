#include "dpc/sim/closed_loop_simulator.h"

#include <cmath>

#include "dpc/config/scenario_builders.h"
#include "dpc/control/polarization_controller.h"
#include "dpc/sim/delay_line.h"
#include "dpc/sim/simulation_run.h"
#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

}  // namespace

ClosedLoopSimulator::ClosedLoopSimulator(const ScenarioConfig& scenario,
                                         ControlLawFactory law_factory)
    : scenario_(scenario),
      custom_law_(static_cast<bool>(law_factory)),
      law_factory_(law_factory ? std::move(law_factory) : MakeControlLaw) {
  ValidateScenario(scenario_);
  chain_ = std::make_unique<WaveplateChain>(BuildChain(scenario_.stages));
  target_ = std::make_unique<Target>(BuildTarget(scenario_.target));
  law_timing_ = BuildLawTiming(scenario_.simulation);
  initial_phi_ = BuildInitialPhi(scenario_.controller, chain_->control_count());
  delay_samples_ = DelaySamples(scenario_.simulation);
  total_samples_ = TotalSamples(scenario_.simulation);
  const double activation = scenario_.controller.activation_s * scenario_.simulation.sample_rate_hz;
  activation_sample_ = static_cast<int64_t>(std::ceil(activation - 1e-9 * std::max(1.0, activation)));
  // Fail here, not in Run, if the law does not fit the device.
  law_factory_(scenario_.controller, law_timing_, chain_->control_count(), target_->is_point());
  fast_path_ = PlanFastPath(scenario_, *chain_, *target_, custom_law_);
}

std::optional<FusedUpdatePlan> ClosedLoopSimulator::PlanFastPath(const ScenarioConfig& scenario,
                                                                 const WaveplateChain& chain,
                                                                 const Target& target,
                                                                 bool custom_law) {
  if (custom_law) return std::nullopt;
  return PlanFusedUpdate(chain, target, scenario.controller);
}

SimulationResult ClosedLoopSimulator::Run(SimulationObserver* observer, int64_t decimation) {
  if (decimation < 1) decimation = 1;
  if (fast_path_) {
    return DispatchStageAxes(fast_path_->axis, fast_path_->stages, [&](const auto& axes) {
      return RunFastPath(axes, observer, decimation);
    });
  }
  return RunGeneral(observer, decimation);
}

ClosedLoopSimulator::~ClosedLoopSimulator() = default;

SimulationResult ClosedLoopSimulator::RunGeneral(SimulationObserver* observer,
                                                 int64_t decimation) {
  const WaveplateChain& chain = *chain_;
  const Target& target = *target_;
  const double dt_s = 1.0 / scenario_.simulation.sample_rate_hz;
  SimulationRun run(scenario_, target, chain.control_count(), total_samples_, observer,
                    decimation);
  PolarizationController controller(chain, target, scenario_.controller, law_timing_, initial_phi_,
                                    law_factory_);
  ChainPose initial_pose;
  chain.ComputePose(controller.phi(), &initial_pose);
  DelayLine<ChainPose> line(delay_samples_, initial_pose);
  ControlInput input;  // the sample clock: one nominal period per update

  // Blocks of up to D samples: a command issued in a block acts D samples later, so never in
  // the same block. Each block first runs the input, the plant and the polarimeters for all its
  // samples (independent of the block's commands), then the controller's updates in order. The
  // results are those of the sample-by-sample loop; the processor overlaps the independent
  // work instead of waiting on the controller's dependency chain.
  const int64_t block = std::min<int64_t>(delay_samples_, kMaxBlock);
  std::vector<StokesVector> in_measured(static_cast<size_t>(block));
  std::vector<StokesVector> out_measured(static_cast<size_t>(block));
  int64_t block_start_slot = 0;  // delay-line slot of the block's first sample
  int64_t k = 0;
  while (k < total_samples_) {
    const int64_t count = std::min(block, total_samples_ - k);
    // Phase 1: input, plant, measurement, statistics of the true output.
    int64_t slot = block_start_slot;
    for (int64_t i = 0; i < count; ++i, slot = line.Next(slot)) {
      const int64_t sample = k + i;
      const double t_s = static_cast<double>(sample) * dt_s;
      const StokesVector& s_in = run.input.Next();
      const ChainPose& applied = line.at(slot);
      const StokesVector s_out = chain.Output(applied, s_in);
      if (sample >= activation_sample_) {
        run.statistics.AddSample(t_s, s_out, applied.phi);
        in_measured[static_cast<size_t>(i)] = run.input_polarimeter.Measure(s_in);
        out_measured[static_cast<size_t>(i)] = run.output_polarimeter.Measure(s_out);
      }
      if (run.TakesSample()) {
        run.observer().OnSample(SampleView{sample, t_s, s_in, s_out, applied.phi,
                                           target.DistanceRad(s_out) * kRadToDeg});
      }
    }
    // Phase 2: the controller, sample by sample; command k + i acts at k + i + D.
    slot = block_start_slot;
    for (int64_t i = 0; i < count; ++i, slot = line.Next(slot)) {
      const int64_t sample = k + i;
      bool issued = false;
      if (sample >= activation_sample_) {
        input.s_in = in_measured[static_cast<size_t>(i)];
        input.s_out = out_measured[static_cast<size_t>(i)];
        const ControlUpdate update = controller.Update(input, line.latest());
        const ControlDiagnostics& diagnostics = controller.diagnostics();
        run.statistics.AddUpdate(diagnostics.nullspace_active, !IsUsable(update.status),
                                 update.status == ControlStatus::kRankDeficient,
                                 update.outcome == ControlIntegrator::Outcome::kClamped,
                                 diagnostics.singular_values);
        if (update.outcome != ControlIntegrator::Outcome::kRejected) {
          chain.ComputePoseFrom(line.latest(), controller.phi(), &line.issue(slot));
          issued = true;
        }
      }
      line.Close(slot, issued);
    }
    block_start_slot = slot;
    k += count;
    if (!run.EndBlock(k)) break;
  }
  return run.Finish(k, controller.diagnostics().resets, controller.phi());
}

}  // namespace dpc
