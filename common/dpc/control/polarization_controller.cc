#include "dpc/control/polarization_controller.h"

#include <cmath>

namespace dpc {
namespace {

/// Samples the predictor needs before a rate command is anything but zero.
constexpr int64_t kRateMinSamples = 16;

}  // namespace

PolarizationController::PolarizationController(const WaveplateChain& chain, const Target& target,
                                               const ControllerConfig& config, const LawTiming& timing,
                                               const ControlVector& initial_phi,
                                               ControlLawFactory law_factory)
    : chain_(chain),
      target_(&target),
      config_(config),
      timing_(timing),
      custom_law_(static_cast<bool>(law_factory)),
      law_factory_(law_factory ? std::move(law_factory) : MakeControlLaw),
      law_(law_factory_(config_, timing_, chain.control_count(), target.is_point())),
      integrator_(chain, initial_phi),
      rate_(ControlVector::Zero(chain.control_count())),
      step_(ControlVector::Zero(chain.control_count())) {
  problem_.chain = &chain_;
  problem_.target = target_;
  problem_.loop_mode = config_.loop;
  problem_.need_jacobian = law_->needs_jacobian();
  if (const auto& prediction = config_.prediction) {
    compensator_.emplace(prediction->window_samples,
                         prediction->lead_samples.value_or(IntegratorLagSamples(config_.step)),
                         1.0 / timing_.sample_rate_hz);
    horizon_samples_ = prediction->horizon_samples.value_or(static_cast<double>(timing_.delay_samples));
  }
  rate_problem_.chain = &chain_;
  rate_problem_.target = target_;
  rate_problem_.pose = &rate_pose_;
  rate_problem_.loop_mode = LoopMode::kModel;
  rate_problem_.need_jacobian = false;
  delta_phi_.resize(chain.control_count());
  fused_ = MakeFusedStep();
}

std::unique_ptr<FusedControlStep> PolarizationController::MakeFusedStep() const {
  if (custom_law_) return nullptr;
  const std::optional<FusedUpdatePlan> plan = PlanFusedUpdate(chain_, *target_, config_);
  if (!plan) return nullptr;
  std::unique_ptr<FusedControlStep> step = FusedControlStep::Make(*plan);
  step->SetCommand(integrator_.phi());
  return step;
}

PolarizationController::~PolarizationController() = default;

void PolarizationController::Reset(const ControlVector& phi) {
  integrator_.Reset(phi);
  if (fused_) fused_->SetCommand(integrator_.phi());
  activated_ = false;
}

void PolarizationController::ForgetInput() {
  if (compensator_) compensator_->Reset();
}

void PolarizationController::SetTarget(const Target& target) {
  if (target.is_point() != target_->is_point()) {
    // A point law and a set law have different task sizes.
    law_ = law_factory_(config_, timing_, chain_.control_count(), target.is_point());
    problem_.need_jacobian = law_->needs_jacobian();
    activated_ = false;
  }
  target_ = &target;
  problem_.target = target_;
  rate_problem_.target = target_;
  fused_ = MakeFusedStep();
}

ControlUpdate PolarizationController::Update(const ControlInput& input) {
  if (fused_) return FusedUpdate(input);
  chain_.ComputePose(integrator_.phi(), &pose_);
  return Update(input, pose_);
}

ControlUpdate PolarizationController::FusedUpdate(const ControlInput& input) {
  if (!activated_) {
    law_->Activate(integrator_.phi());
    activated_ = true;
  }
  const FusedUpdateResult result = fused_->Update(input.s_in, input.s_out, &delta_phi_);
  fused_diagnostics_.rank = result.rank;
  fused_diagnostics_.singular_values = result.singular_values;
  fused_diagnostics_.nullspace_active = result.nullspace_active;
  ControlUpdate update;
  update.status = !result.applied ? ControlStatus::kNotFinite
                  : result.rank < 2 ? ControlStatus::kRankDeficient
                                    : ControlStatus::kOk;
  // The integrator adds the same Δφ the fused step added to its command (the same bits).
  update.outcome = integrator_.Apply(update.status, delta_phi_);
  return update;
}

ControlUpdate PolarizationController::Update(const ControlInput& input, const ChainPose& pose) {
  if (fused_) {
    fused_->SetPose(pose);
    return FusedUpdate(input);
  }
  if (!activated_) {
    law_->Activate(integrator_.phi());
    activated_ = true;
  }
  problem_.pose = &pose;
  const bool rate_command = input.rate_command && compensator_ && input.time_ns;
  if (!compensator_) {
    problem_.s_in = input.s_in;
  } else if (!input.time_ns) {
    problem_.s_in = compensator_->Predict(input.s_in, horizon_samples_);
  } else {
    if (compensator_->predictor().samples() == 0) time_origin_ns_ = *input.time_ns;
    // A rate command takes the measured input (horizon 0: the latest sample itself) and uses
    // the horizon only for the rate's midpoint; otherwise the law aims at the prediction.
    problem_.s_in = compensator_->PredictAt(input.s_in,
                                            static_cast<double>(*input.time_ns - time_origin_ns_) * 1e-9,
                                            rate_command ? 0.0 : input.horizon_s);
  }
  problem_.s_out_measured = input.s_out;
  UpdateControlProblem(&problem_);
  if (compensator_ && !rate_command) compensator_->AddLead(&problem_);
  ControlUpdate update;
  update.status = law_->ComputeUpdate(problem_, &delta_phi_);
  update.outcome = integrator_.Apply(update.status, delta_phi_);
  if (rate_command) ComputeRate(input.horizon_s);
  return update;
}

void PolarizationController::AdvanceAlongRate(double dt_s) {
  step_ = rate_ * dt_s;
  integrator_.Apply(ControlStatus::kOk, step_);
  if (fused_) fused_->SetCommand(integrator_.phi());
}

void PolarizationController::SolveRate(const ControlProblem& problem, const Vector3& omega,
                                       ControlVector* rate) {
  // The input moves by ω × S_in (rad/s, input frame); φ̇ must cancel what that does to the
  // task: T φ̇ = the rate of the task error it causes (−Eᵀ(ω × S_in) for a point target).
  TaskVector velocity;
  TaskErrorChangeOfInput(problem, omega.cross(problem.s_in), &velocity);
  const SingularityDampingConfig damping = config_.singularity_damping.value_or(SingularityDampingConfig{});
  rate_solver_.ComputeDamped(problem.task_jacobian, damping.max_damping, damping.threshold);
  rate_solver_.Solve(velocity, rate);
}

void PolarizationController::ComputeRate(double horizon_s) {
  const InputPredictor& predictor = compensator_->predictor();
  if (predictor.samples() < kRateMinSamples) {
    rate_.setZero();
    return;
  }
  const Vector3 omega = predictor.RotationPerSample() / predictor.nominal_sample_period_s();
  // The rate where the update left the task (φ before the step, the measured input)...
  SolveRate(problem_, omega, &rate_);
  if (horizon_s > 0.0) {
    // ...then again halfway to where the command will act (φ moved by that rate, the input
    // predicted there).
    const double half_s = 0.5 * horizon_s;
    step_ = integrator_.phi() + rate_ * half_s;
    chain_.ComputePose(step_, &rate_pose_);
    rate_problem_.s_in = predictor.PredictSeconds(half_s);
    rate_problem_.s_out_measured = rate_problem_.s_in;
    UpdateControlProblem(&rate_problem_);
    SolveRate(rate_problem_, omega, &rate_);
  }
  if (!rate_.allFinite()) rate_.setZero();
}

}  // namespace dpc
