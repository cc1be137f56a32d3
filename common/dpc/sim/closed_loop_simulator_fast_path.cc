// The simulator's fast path for the paper's class of configurations (PlanFusedUpdate: 3 or 4
// fixed-axis stages on S1/S2/S3 with θ = k·φ + θ0 and no ranges, a point target, gp / gpt /
// pinv, either loop mode): the fused control update (control/fused_gradient_projection.h)
// inlined into the sample loop, with the paper's devices' axes fixed at compile time.
//
// Per sample, in the general loop's order: the input, the plant (ElementalOutput with the pose of
// the command issued D samples ago), the statistics of the true output, the polarimeters, then
// the controller's update at its latest command, whose pose goes into the delay line. Only the
// update depends on the previous update; the processor runs the rest in the shadow of that
// dependency chain, which is why the loop goes sample by sample (the general loop's blocks of D
// samples, input first, then the updates, would make the two add up instead).
//
// It shares the input generator, the polarimeters, the statistics and the near-singular
// fallback with the general loop. Only round-off separates the two loops' trajectories.

#include <cmath>

#include "dpc/control/fused_gradient_projection.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/delay_line.h"
#include "dpc/sim/simulation_run.h"

namespace dpc {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

}  // namespace

template <typename Axes>
SimulationResult ClosedLoopSimulator::RunFastPath(const Axes& axes, SimulationObserver* observer,
                                                  int64_t decimation) {
  constexpr int N = Axes::kStages;
  using Pose = ElementalPose<N>;
  const double dt_s = 1.0 / scenario_.simulation.sample_rate_hz;
  const Target& target = *target_;

  SimulationRun run(scenario_, target, N, total_samples_, observer, decimation);
  FusedGradientProjection<Axes> controller(*fast_path_, axes);

  // The controller's command, kept in registers across updates; the delay line holds copies.
  Pose command;
  for (int e = 0; e < N; ++e) command.phi[e] = initial_phi_[e];
  controller.ExactPose(&command);
  DelayLine<Pose> line(delay_samples_, command);

  ControlVector observed_phi(N);
  double delta_phi[N];

  // Sample by sample: the input, the plant (the command of D samples ago), the statistics and
  // the measurements do not depend on the controller's latest update, so the processor runs
  // them in the shadow of the controller's dependency chain.
  int64_t slot = 0, k = 0;
  while (k < total_samples_) {
    // Progress (and an early stop) as often as the general loop's blocks end.
    const int64_t end = std::min(total_samples_, k + kMaxBlock);
    for (; k < end; ++k, slot = line.Next(slot)) {
      const double t_s = static_cast<double>(k) * dt_s;
      const StokesVector& s_in = run.input.Next();
      const Pose& applied = line.at(slot);
      const StokesVector s_out = ElementalOutput(axes, applied, s_in);
      if (run.TakesSample()) {
        for (int e = 0; e < N; ++e) observed_phi[e] = applied.phi[e];
        run.observer().OnSample(SampleView{k, t_s, s_in, s_out, observed_phi,
                                           target.DistanceRad(s_out) * kRadToDeg});
      }
      bool issued = false;
      if (k >= activation_sample_) {
        run.statistics.AddSample(t_s, s_out, ToArray(applied.phi).data());
        const StokesVector in_measured = run.input_polarimeter.Measure(s_in);
        const StokesVector out_measured = run.output_polarimeter.Measure(s_out);
        const FusedUpdateResult update =
            controller.Update(in_measured, out_measured, &command, delta_phi);
        run.statistics.AddUpdate(update.nullspace_active, !update.applied,
                                 update.applied && update.rank < 2, false, update.singular_values);
        if (update.applied) {
          line.issue(slot) = command;
          issued = true;
        }
      }
      line.Close(slot, issued);
    }
    if (!run.EndBlock(k)) break;
  }
  ControlVector final_phi(N);
  for (int e = 0; e < N; ++e) final_phi[e] = command.phi[e];
  return run.Finish(k, 0, final_phi);
}

template SimulationResult ClosedLoopSimulator::RunFastPath(const PaperAxes3&, SimulationObserver*,
                                                           int64_t);
template SimulationResult ClosedLoopSimulator::RunFastPath(const PaperAxes4&, SimulationObserver*,
                                                           int64_t);
template SimulationResult ClosedLoopSimulator::RunFastPath(const RuntimeStageAxes<3>&,
                                                           SimulationObserver*, int64_t);
template SimulationResult ClosedLoopSimulator::RunFastPath(const RuntimeStageAxes<4>&,
                                                           SimulationObserver*, int64_t);

}  // namespace dpc
