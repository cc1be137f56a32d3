#pragma once
// The controller of a dynamic polarization control loop: one update per sample, the same for
// the simulator (sim/closed_loop_simulator) and the DDS controller service, so that both loops
// take the same step by construction.
//
// An update at sample k (paper §II–III, eqs. 3, 5, 6):
//   1. the task at the controller's command φ[k] and the measured S_in (UpdateControlProblem:
//      J, the reduced task T and its error e from ΔS_out = S* − S_out, eq. 5);
//   2. the law's Δφ from the linear model J Δφ = ΔS_out (eq. 3; any ControlLaw, chosen by
//      ControllerConfig::method);
//   3. the integrator's new command φ[k+1] = φ[k] + Δφ (eq. 6), kept inside the ranges; an
//      update that failed or is not finite is never applied.
// The law is activated (ControlLaw::Activate) from φ at the first update after construction
// or Reset: a bumpless start from what the device applies.
//
// Delay compensation (ControllerConfig::prediction, delay_compensator.h): the task is taken at
// the input SOP predicted for the moment the command acts, plus the lead that removes the
// integrator's lag. Two clocks:
//   - the sample clock (ControlInput::time_ns unset): each update is one nominal sample period
//     after the previous one, and the horizon is the configured one (horizon_samples, else the
//     loop delay in samples): the simulator, bit for bit as it has always run;
//   - bench time (time_ns set): the samples are observed at their times, and the horizon is the
//     caller's (ControlInput::horizon_s: the DDS controller measures its loop latency).
//
// Rate commands (ControlInput::rate_command, bench time only). The command carries φ̇, the rate
// that keeps the output still while the input turns at the fitted rate ω (rad/s, input frame):
// the task's differential kinematics with a moving input (eq. 3 with Ṡ_in = ω × S_in):
//   point target:  T φ̇ = −Eᵀ(ω × S_in)          (T, E: the reduced task, control_problem.h)
//   set target:    nᵀJ φ̇ = −(Mᵀn)·(ω × S_in)
// solved with the damped task pseudo-inverse (minimum norm: no null-space motion), evaluated
// halfway across horizon_s (φ moved by that rate, the input predicted there): the ramp is a
// chord of the curved φ trajectory, and the midpoint's slope meets it at the horizon to second
// order. Such an update aims at the measured input (no prediction, no lead): the driver moves
// the waveplates along the ramp, and AdvanceAlongRate moves φ with them before the next update.
//
// The paper's configurations (PlanFusedUpdate: 3 or 4 stages on S1/S2/S3 with θ = k·φ + θ0,
// gp / gpt / pinv, a point target, none of the options, the built-in laws) run the fused
// update (fused_gradient_projection.h): the same step in one fixed-size pass, equal to the
// general path to round-off. It keeps the pose of the command itself (incremental sines and
// cosines, as the simulator does), so Update(input) costs no library sine; a pose passed in is
// taken as it is. problem() is the general path's only.
//
// Real-time: Update and AdvanceAlongRate do not allocate.

#include <cstdint>
#include <memory>
#include <optional>

#include "dpc/control/control_integrator.h"
#include "dpc/control/control_law.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/control/control_problem.h"
#include "dpc/control/controller_config.h"
#include "dpc/control/delay_compensator.h"
#include "dpc/control/fused_gradient_projection.h"
#include "dpc/control/target.h"
#include "dpc/control/task_pseudo_inverse.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

/// One sample as the controller sees it.
struct ControlInput {
  StokesVector s_in = StokesVector::UnitX();   ///< measured input SOP
  StokesVector s_out = StokesVector::UnitX();  ///< measured output SOP
  /// The sample's bench time; unset: one nominal period after the previous update's sample.
  std::optional<int64_t> time_ns;
  /// Bench time with delay compensation: how long after the sample the command acts.
  double horizon_s = 0.0;
  /// Bench time with delay compensation: compute a rate command (rate_per_s()) instead of
  /// aiming at the prediction.
  bool rate_command = false;
};

/// What one update did.
struct ControlUpdate {
  ControlStatus status = ControlStatus::kOk;
  ControlIntegrator::Outcome outcome = ControlIntegrator::Outcome::kApplied;
};

class PolarizationController {
 public:
  /// `chain` and `target` outlive the controller; `config` passed ValidateControllerConfig for
  /// this chain and target. The command starts at `initial_phi` (clamped into the ranges).
  /// `law_factory` (optional) replaces MakeControlLaw. Throws std::invalid_argument if the law
  /// does not fit the chain and target, or `initial_phi` has the wrong size.
  PolarizationController(const WaveplateChain& chain, const Target& target,
                         const ControllerConfig& config, const LawTiming& timing,
                         const ControlVector& initial_phi, ControlLawFactory law_factory = nullptr);
  ~PolarizationController();

  /// Not real-time. The command becomes `phi` (clamped into the ranges); the law is activated
  /// from it at the next update (bumpless re-join).
  void Reset(const ControlVector& phi);
  /// Not real-time. Forgets the input's history (the predictor), e.g. after a gap in the samples.
  void ForgetInput();
  /// Not real-time. A new target (outlives the controller); the law is rebuilt and re-activated
  /// when its kind (point or set) changes. Throws std::invalid_argument if the law does not fit.
  void SetTarget(const Target& target);

  /// Real-time. One update from `input`, with `pose` the chain at phi() (the caller keeps it,
  /// e.g. the simulator's delay line). After it, phi() is the new command.
  ControlUpdate Update(const ControlInput& input, const ChainPose& pose);
  /// Real-time. The same with the pose computed here (on the fused path: carried over from the
  /// previous update, exact after a Reset).
  ControlUpdate Update(const ControlInput& input);

  /// Real-time. Moves the command along the latest rate for `dt_s` (the waveplates followed
  /// the ramp): φ += rate_per_s()·dt_s.
  void AdvanceAlongRate(double dt_s);

  /// The command: φ after the latest update.
  const ControlVector& phi() const { return integrator_.phi(); }
  /// The rate of the latest update with ControlInput::rate_command (zero before any).
  const ControlVector& rate_per_s() const { return rate_; }
  const ControlLaw& law() const { return *law_; }
  const ControlDiagnostics& diagnostics() const {
    return fused_ ? fused_diagnostics_ : law_->diagnostics();
  }
  /// Whether the updates run the fused update (see the file comment).
  bool fused() const { return fused_ != nullptr; }
  /// The latest update's task on the general path: s_out_measured, the model output, the task
  /// error (not kept on the fused path).
  const ControlProblem& problem() const { return problem_; }
  /// The delay compensation, if configured.
  const DelayCompensator* compensator() const { return compensator_ ? &*compensator_ : nullptr; }
  const WaveplateChain& chain() const { return chain_; }
  const Target& target() const { return *target_; }

 private:
  /// The fused update for the chain, the current target and the configuration at the command
  /// phi(), or null when they are not in its class or a law factory was given.
  std::unique_ptr<FusedControlStep> MakeFusedStep() const;
  /// Update on the fused path, at its command.
  ControlUpdate FusedUpdate(const ControlInput& input);
  /// The rate for the current task (see the file comment), evaluated halfway across `horizon_s`.
  void ComputeRate(double horizon_s);
  /// φ̇ for `problem`'s task and basis and an input turning at ω (rad/s).
  void SolveRate(const ControlProblem& problem, const Vector3& omega, ControlVector* rate);

  const WaveplateChain& chain_;
  const Target* target_;
  ControllerConfig config_;
  LawTiming timing_;
  bool custom_law_;  ///< a law factory was given: never the fused path
  ControlLawFactory law_factory_;
  std::unique_ptr<ControlLaw> law_;
  std::unique_ptr<FusedControlStep> fused_;
  ControlDiagnostics fused_diagnostics_;
  ControlIntegrator integrator_;
  bool activated_ = false;
  ControlProblem problem_;
  ChainPose pose_;               ///< Update(input) only
  ControlVector delta_phi_;

  std::optional<DelayCompensator> compensator_;
  double horizon_samples_ = 0.0;  ///< the sample clock's prediction horizon
  int64_t time_origin_ns_ = 0;    ///< the predictor's t = 0 in bench time (keeps seconds exact)

  ControlVector rate_;
  ControlVector step_;            ///< scratch
  TaskPseudoInverse rate_solver_;
  ChainPose rate_pose_;
  ControlProblem rate_problem_;
};

}  // namespace dpc
