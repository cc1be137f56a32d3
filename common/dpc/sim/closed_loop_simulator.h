#pragma once
// The closed-loop simulator: the paper's section IV experiment, sample by sample.
//
// Per sample k (t = k/f_s), in this order:
//   1. input     S_in[k] from the disturbances (InputSopGenerator)
//   2. plant     the waveplates apply the command issued at sample k − D (D = loop delay in
//                samples; before that, the initial φ): S_out[k] = f(φ_applied; S_in[k])
//   3. measure   both polarimeters, with optional noise
//   4. record    true error ∠(S_out[k], target), leak, applied φ (from activation on)
//   5. control   from the activation time on: the law computes Δφ from the measurements (loop
//                mode: model S_out or measured S_out), the integrator adds it (eq. 6); the new
//                command acts from sample k + D. "The Δφ obtained at time t is used to update
//                the control signal at t + τ" (paper section IV).
//
// Speed: each command's ChainPose (its sines and cosines) is computed once, when the controller
// issues it, and kept in the delay line, so the plant reuses it D samples later. The delay line
// holds D poses and the statistics are fixed-size histograms: memory does not grow with the
// run length. Nothing in the per-sample loop allocates.
//
// Two loops, the same results: the general loop runs any device, law (including a user's) and
// target through PolarizationController / ControlLaw; the fast path, selected automatically for
// the paper's class of configurations (PlanFusedUpdate: 3 or 4 fixed-axis stages on S1/S2/S3
// with linear maps and no ranges, a point target, gp / gpt / pinv, either loop mode, any input
// and noise), inlines the fused control update into one fixed-size loop body
// (closed_loop_simulator_fast_path.cc). Its trajectories equal the general loop's to round-off
// (tests/unit/sim/closed_loop_simulator_fast_path_test.cc).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/control/control_integrator.h"
#include "dpc/control/control_law.h"
#include "dpc/control/fused_gradient_projection.h"
#include "dpc/disturbance/input_sop_generator.h"
#include "dpc/disturbance/polarimeter_noise.h"
#include "dpc/optics/waveplate_chain.h"
#include "dpc/sim/run_statistics.h"

namespace dpc {

/// One sample as the observer sees it (valid only during the call).
struct SampleView {
  int64_t index;
  double t_s;
  const StokesVector& s_in;
  const StokesVector& s_out;
  const ControlVector& phi_applied;
  double error_deg;
};

class SimulationObserver {
 public:
  virtual ~SimulationObserver() = default;
  /// Called for every `decimation`-th sample (index 0, decimation, 2·decimation, …), if
  /// wants_samples().
  virtual void OnSample(const SampleView& sample) { (void)sample; }
  /// False to receive progress only (the loop then skips building sample views).
  virtual bool wants_samples() const { return true; }
  /// Called every kProgressInterval samples and at the end; return false to stop the run early
  /// (the summary then covers the samples simulated so far).
  virtual bool OnProgress(int64_t done, int64_t total) {
    (void)done;
    (void)total;
    return true;
  }
};

struct SimulationResult {
  RunSummary summary;
  double wall_time_s = 0.0;
  double samples_per_s = 0.0;
  bool stopped_early = false;
  ControlVector final_phi;
};

class ClosedLoopSimulator {
 public:
  /// OnProgress comes about this often (at the end of the block that crosses each multiple).
  static constexpr int64_t kProgressInterval = int64_t{1} << 20;
  /// The most samples processed per phase (see Run).
  static constexpr int64_t kMaxBlock = 64;

  /// Validates the scenario (ValidateScenario: throws ScenarioError naming the bad field) and
  /// builds the device, target, law, input and polarimeters.
  /// `law_factory` (optional) replaces MakeControlLaw.
  explicit ClosedLoopSimulator(const ScenarioConfig& scenario,
                               ControlLawFactory law_factory = nullptr);
  ~ClosedLoopSimulator();

  /// Runs the whole scenario. Not re-entrant; each call starts from the scenario's initial
  /// state with the same seed, so two calls give identical results.
  SimulationResult Run(SimulationObserver* observer = nullptr, int64_t decimation = 1);

  const ScenarioConfig& scenario() const { return scenario_; }
  const WaveplateChain& chain() const { return *chain_; }
  const Target& target() const { return *target_; }
  int64_t delay_samples() const { return delay_samples_; }
  /// Whether Run uses the fused fast path (see the file comment).
  bool uses_fast_path() const { return fast_path_.has_value(); }
  int64_t total_samples() const { return total_samples_; }
  int64_t activation_sample() const { return activation_sample_; }
  /// The fused update's plan when Run uses the fast path (the batched simulator runs the same).
  const std::optional<FusedUpdatePlan>& fast_path_plan() const { return fast_path_; }
  /// The command before the first update.
  const ControlVector& initial_phi() const { return initial_phi_; }

 private:
  /// The fused update's plan if the scenario is in the fast path's class, else nullopt.
  static std::optional<FusedUpdatePlan> PlanFastPath(const ScenarioConfig& scenario,
                                                     const WaveplateChain& chain,
                                                     const Target& target, bool custom_law);
  SimulationResult RunGeneral(SimulationObserver* observer, int64_t decimation);
  template <typename Axes>
  SimulationResult RunFastPath(const Axes& axes, SimulationObserver* observer, int64_t decimation);

  ScenarioConfig scenario_;
  bool custom_law_;
  std::unique_ptr<WaveplateChain> chain_;
  std::unique_ptr<Target> target_;
  LawTiming law_timing_;
  ControlLawFactory law_factory_;
  ControlVector initial_phi_;
  int64_t delay_samples_ = 1;
  int64_t total_samples_ = 0;
  int64_t activation_sample_ = 0;
  std::optional<FusedUpdatePlan> fast_path_;
};

}  // namespace dpc
