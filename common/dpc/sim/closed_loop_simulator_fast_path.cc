// The simulator's fast path for the paper's class of configurations (PlanFusedUpdate: 3 or 4
// fixed-axis stages on S1/S2/S3 with θ = k·φ + θ0 and no ranges, a point target, gp / gpt /
// pinv, either loop mode): the fused control update (control/fused_gradient_projection.h)
// inlined into the sample loop, with the paper's devices' axes fixed at compile time.
//
// Per sample: the input, the plant (ElementalOutput with the pose of the command issued D
// samples ago), the statistics of the true output, the polarimeters, and the controller's update
// at its latest command, whose pose goes into the delay line. Only the updates depend on each
// other; the processor runs the rest in the shadow of that dependency chain, which is why the
// loop goes sample by sample (the general loop's blocks of D samples, input first, then the
// updates, would make the two add up) and observes each sample one update ahead (see the loop).
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

  // What the controller reads of a sample: both polarimeters' readings.
  struct Measured {
    StokesVector s_in, s_out;
  };
  Measured measured[2];  // sample k in measured[k & 1]
  // The input, the plant (the command of D samples ago), the observer, the statistics and the
  // polarimeters of `sample`, whose pose is in `slot`.
  // The input a block at a time: its random draws batched, its rotations interleaved here.
  constexpr int64_t kInputBlock = InputSopGenerator::kMaxBlock;
  static_assert((kInputBlock & (kInputBlock - 1)) == 0, "sample & (kInputBlock - 1) is the index");
  InputSopGenerator::BlockCursor input_cursor{};
  const auto observe = [&](int64_t sample, int64_t slot) __attribute__((always_inline)) {
    const double t_s = static_cast<double>(sample) * dt_s;
    const int in_block = static_cast<int>(sample & (kInputBlock - 1));
    if (in_block == 0) {
      input_cursor =
          run.input.BeginBlock(static_cast<int>(std::min(kInputBlock, total_samples_ - sample)));
    }
    const StokesVector s_in = run.input.Step(in_block, &input_cursor);
    if (in_block == kInputBlock - 1 || sample + 1 == total_samples_) {
      run.input.EndBlock(input_cursor);
    }
    const Pose& applied = line.at(slot);
    const StokesVector s_out = ElementalOutput(axes, applied, s_in);
    if (run.TakesSample()) {
      for (int e = 0; e < N; ++e) observed_phi[e] = applied.phi[e];
      run.observer().OnSample(SampleView{sample, t_s, s_in, s_out, observed_phi,
                                         target.DistanceRad(s_out) * kRadToDeg});
    }
    if (sample >= activation_sample_) {
      run.statistics.AddSample(t_s, s_out, ToArray(applied.phi).data());
      Measured& m = measured[sample & 1];
      m.s_in = run.input_polarimeter.Measure(s_in);
      m.s_out = run.output_polarimeter.Measure(s_out);
    }
  };

  // Only the controller's updates depend on each other. Sample k + 1 is observed before the
  // update of sample k (its command was issued D ≥ 2 samples before): the processor then has
  // the next sample's work in hand while the update's dependency chain runs, and the update
  // finds its readings long computed. With D = 1 the next sample needs this update's command.
  const int64_t lead = delay_samples_ >= 2 ? 1 : 0;
  int64_t slot = 0, k = 0;
  if (lead > 0 && total_samples_ > 0) observe(0, 0);
  while (k < total_samples_) {
    // Progress (and an early stop) as often as the general loop's blocks end.
    const int64_t end = std::min(total_samples_, k + kMaxBlock);
    for (; k < end; ++k, slot = line.Next(slot)) {
      if (lead == 0) {
        observe(k, slot);
      } else if (k + 1 < total_samples_) {
        observe(k + 1, line.Next(slot));
      }
      bool issued = false;
      if (k >= activation_sample_) {
        const Measured& m = measured[k & 1];
        const FusedUpdateResult update = controller.Update(m.s_in, m.s_out, &command, delta_phi);
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
