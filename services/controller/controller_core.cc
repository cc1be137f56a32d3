#include "controller_core.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::services {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int64_t kRateMinSamples = 16;  ///< samples the predictor needs before a rate is sent
}

ControllerCore::ControllerCore(ControllerSettings settings) : settings_(std::move(settings)) {
  law_name_ = std::string(MethodName(settings_.controller.method));
}

ControllerCore::~ControllerCore() = default;

std::string ControllerCore::OnDevice(const msg::DeviceDescription& description) {
  try {
    std::vector<StageConfig> stages = bus::StagesFromDescription(description);
    const int controls = ScenarioControlCount(stages);
    // The law must fit the device and the current target (inverse needs a square task).
    TargetConfig target_config;
    if (target_) {
      target_config.kind = target_->is_point() ? TargetConfig::Kind::kPoint : TargetConfig::Kind::kSet;
    }
    ValidateControllerConfig(settings_.controller, controls, target_config, settings_.simulation);
    auto chain = std::make_unique<WaveplateChain>(BuildChain(stages));
    law_for_point_ = target_config.kind == TargetConfig::Kind::kPoint;
    auto law = MakeControlLaw(settings_.controller, BuildLawTiming(settings_.simulation), controls, law_for_point_);
    chain_ = std::move(chain);
    law_ = std::move(law);
    integrator_ = std::make_unique<ControlIntegrator>(*chain_, ControlVector::Zero(controls));
    applied_phi_ = ControlVector::Zero(controls);
    applied_motion_.phi = ControlVector::Zero(controls);
    applied_motion_.rate_per_s = ControlVector::Zero(controls);
    applied_motion_.moving = false;
    rate_ = ControlVector::Zero(controls);
    step_ = ControlVector::Zero(controls);
    rate_time_ns_ = 0;
    ramp_ = false;
    device_max_ramp_s_ = description.max_ramp_s() > 0.0 && std::isfinite(description.max_ramp_s())
                             ? description.max_ramp_s()
                             : 0.0;
    have_state_ = false;
    activated_ = false;
    problem_.chain = chain_.get();
    problem_.loop_mode = settings_.controller.loop;
    problem_.need_jacobian = law_->needs_jacobian();
    compensator_.reset();
    if (const auto& prediction = settings_.controller.prediction) {
      compensator_.emplace(prediction->window_samples,
                           prediction->lead_samples.value_or(IntegratorLagSamples(settings_.controller.step)),
                           1.0 / settings_.simulation.sample_rate_hz);
    }
    latency_estimate_s_ = -1.0;
    condition_ = target_ ? "waiting for the driver's state" : "waiting for the target";
    return {};
  } catch (const std::exception& e) {
    condition_ = fmt::format("unusable device description: {}", e.what());
    return condition_;
  }
}

std::string ControllerCore::OnTarget(const msg::Target& message) {
  if (message.revision() <= target_revision_ && target_) return {};  // already have it
  try {
    const TargetConfig config = bus::TargetFromMessage(message);
    target_ = std::make_unique<Target>(BuildTarget(config));
    target_revision_ = message.revision();
    if (chain_ && law_for_point_ != target_->is_point()) {
      // A point law and a set law have different task sizes: rebuild the law.
      law_ = MakeControlLaw(settings_.controller, BuildLawTiming(settings_.simulation),
                            chain_->control_count(), target_->is_point());
      law_for_point_ = target_->is_point();
      problem_.need_jacobian = law_->needs_jacobian();
      activated_ = false;
    }
    problem_.target = target_.get();
    if (!chain_) condition_ = "waiting for the device description";
    else if (!have_state_) condition_ = "waiting for the driver's state";
    return {};
  } catch (const std::exception& e) {
    condition_ = fmt::format("unusable target: {}", e.what());
    return condition_;
  }
}

void ControllerCore::Resync(const ControlVector& phi) {
  integrator_->Reset(phi);
  activated_ = false;
}

void ControllerCore::OnState(const msg::WaveplateState& state) {
  if (!chain_) return;
  if (std::string reason = bus::CheckStateShape(state, chain_->control_count()); !reason.empty()) {
    RejectSample("state: " + reason);
    return;
  }
  bus::ReadTrajectory(state, &applied_motion_);
  applied_motion_.At(last_sample_time_ns_, &applied_phi_);
  const bool first = !have_state_;
  have_state_ = true;
  obeyed_ = state.mode() == msg::DRIVER_ACTIVE &&
            state.obeyed_controller_id().to_string() == settings_.controller_id;
  if (first) {
    Resync(applied_phi_);
    return;
  }
  if (obeyed_) {
    state_answers_sample_ = state.answers_sample();
    if (state.answers_sample() == last_answered_sample_) {
      for (bool limited : state.saturated()) {
        if (limited) {
          Resync(applied_phi_);  // the driver clamped our latest command: no wind-up
          break;
        }
      }
    }
    return;
  }
  // Not obeyed: follow what is applied, so that the first obeyed command continues from there.
  // One exception keeps a lockstep run exact: a holding heartbeat the driver sent before it saw
  // our latest command (it answers an older sample) must not undo that command. In real time
  // such a race costs at most one step, and following every heartbeat matters more (a
  // controller whose commands have not reached the driver yet must not drift on its own).
  const bool stale_heartbeat = state.mode() == msg::DRIVER_HOLDING && lockstep_ &&
                               state.answers_sample() < last_answered_sample_;
  if (!stale_heartbeat) Resync(applied_phi_);
}

double ControllerCore::PredictionHorizonS(const msg::StokesSample& sample) {
  const PredictionConfig& prediction = *settings_.controller.prediction;
  const double period_s = 1.0 / settings_.simulation.sample_rate_hz;
  if (prediction.horizon_samples) return *prediction.horizon_samples * period_s;
  if (sample.lockstep()) return settings_.simulation.delay_s;  // the simulated bench's own delay
  const auto& [sequence, time_ns] = sample_times_ns_[state_answers_sample_ % kSampleTimeRing];
  if (obeyed_ && state_answers_sample_ != 0 && sequence == state_answers_sample_) {
    const double latency_s = static_cast<double>(sample.sample_time_ns() - time_ns) * 1e-9;
    if (latency_s >= 0.0 && latency_s < 0.5) {
      latency_estimate_s_ = latency_estimate_s_ < 0.0
                                ? latency_s
                                : latency_estimate_s_ + (latency_s - latency_estimate_s_) / 64.0;
    }
  }
  // Before the first measurement (or while another controller is obeyed): the last estimate,
  // else one sample period. Whole microseconds: the compensator re-solves its cached fit when
  // the horizon changes.
  return latency_estimate_s_ >= 0.0 ? std::round(latency_estimate_s_ * 1e6) * 1e-6 : period_s;
}

void ControllerCore::SolveRate(const ControlProblem& problem, const Vector3& omega, ControlVector* rate) {
  // The input moves by ω × S_in (rad/s, input frame); φ̇ must cancel what that does to the
  // task: T φ̇ = the rate of the task error it causes (−Eᵀ(ω × S_in) for a point target).
  TaskVector velocity;
  TaskErrorChangeOfInput(problem, omega.cross(problem.s_in), &velocity);
  const SingularityDampingConfig damping =
      settings_.controller.singularity_damping.value_or(SingularityDampingConfig{});
  rate_solver_.ComputeDamped(problem.task_jacobian, damping.max_damping, damping.threshold);
  rate_solver_.Solve(velocity, rate);
}

void ControllerCore::ComputeRate(double horizon_s) {
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
    // predicted there): the ramp is a chord of the curved φ trajectory, and the midpoint's
    // slope makes it meet the trajectory at the horizon to second order.
    const double half_s = 0.5 * horizon_s;
    step_ = integrator_->phi() + rate_ * half_s;
    chain_->ComputePose(step_, &rate_pose_);
    rate_problem_.chain = chain_.get();
    rate_problem_.target = target_.get();
    rate_problem_.pose = &rate_pose_;
    rate_problem_.loop_mode = LoopMode::kModel;
    rate_problem_.need_jacobian = false;
    rate_problem_.s_in = predictor.PredictSeconds(half_s);
    rate_problem_.s_out_measured = rate_problem_.s_in;
    UpdateControlProblem(&rate_problem_);
    SolveRate(rate_problem_, omega, &rate_);
  }
  if (!rate_.allFinite()) rate_.setZero();
}

void ControllerCore::RejectSample(std::string reason) {
  ++rejected_samples_;
  last_rejection_ = std::move(reason);
}

const msg::WaveplateCommand* ControllerCore::OnSample(const msg::StokesSample& sample,
                                                              int64_t now_ns, int64_t wall_ns) {
  if (std::string reason = bus::CheckStokesSample(sample); !reason.empty()) {
    RejectSample(reason);
    return nullptr;
  }
  if (!configured()) return nullptr;
  if (sample.sequence_number() == last_sample_ && last_command_ &&
      last_command_->answers_sample() == last_sample_) {
    // The same sample again: a lockstep bench re-publishes when its answer was lost (the
    // periodic topics are best effort). Answer it again, without integrating twice.
    last_command_->publish_time_ns(wall_ns);
    return &*last_command_;
  }
  if (sample.sequence_number() <= last_sample_) {
    // Out of order or repeated (a restarted bench starts again at 1: accept after a gap).
    if (now_ns - last_sample_ns_ < static_cast<int64_t>(settings_.freeze_after_s * 1e9)) return nullptr;
  }
  if (last_sample_ns_ != 0 &&
      now_ns - last_sample_ns_ > static_cast<int64_t>(settings_.freeze_after_s * 1e9)) {
    Resync(applied_phi_);  // samples resume after a gap: re-join from what is applied
    if (compensator_) compensator_->Reset();  // the input's history is stale
  }
  last_sample_ = sample.sequence_number();
  last_sample_ns_ = now_ns;
  lockstep_ = sample.lockstep();
  const int64_t t_ns = sample.sample_time_ns();
  last_sample_time_ns_ = t_ns;
  // Ramp mode needs a driver that ramps; otherwise a predicting controller aims at a point.
  const bool ramp = compensator_ && !lockstep_ && device_max_ramp_s_ > 0.0 &&
                    settings_.prediction_mode == PredictionMode::kRamp;
  if (applied_motion_.moving) {
    applied_motion_.At(t_ns, &applied_phi_);
    if (!obeyed_) Resync(applied_phi_);  // standby: follow the motion where it is now
  }
  if (obeyed_ && ramp && ramp_ && rate_time_ns_ != 0) {
    // The waveplates moved along the latest command's ramp since its sample: so does φ.
    const double dt_s = std::clamp(static_cast<double>(t_ns - rate_time_ns_) * 1e-9, 0.0, device_max_ramp_s_);
    step_ = rate_ * dt_s;
    integrator_->Apply(ControlStatus::kOk, step_);
  }

  const auto start = std::chrono::steady_clock::now();
  if (!activated_) {
    law_->Activate(integrator_->phi());
    activated_ = true;
  }
  chain_->ComputePose(integrator_->phi(), &pose_);
  problem_.pose = &pose_;
  if (compensator_) {
    sample_times_ns_[sample.sequence_number() % kSampleTimeRing] = {sample.sequence_number(), t_ns};
    horizon_s_ = PredictionHorizonS(sample);
    if (compensator_->predictor().samples() == 0) time_origin_ns_ = t_ns;
    // Rate commands take the measured input (horizon 0: the latest sample itself) and use the
    // horizon only for the rate's midpoint; otherwise the law aims at the prediction.
    problem_.s_in = compensator_->PredictAt(bus::ToStokes(sample.s_in()),
                                            static_cast<double>(t_ns - time_origin_ns_) * 1e-9,
                                            ramp ? 0.0 : horizon_s_);
  } else {
    problem_.s_in = bus::ToStokes(sample.s_in());
  }
  problem_.s_out_measured = bus::ToStokes(sample.s_out());
  UpdateControlProblem(&problem_);
  if (compensator_ && !ramp) compensator_->AddLead(&problem_);
  const ControlStatus status = law_->ComputeUpdate(problem_, &delta_phi_);
  const ControlIntegrator::Outcome outcome = integrator_->Apply(status, delta_phi_);
  if (ramp) ComputeRate(horizon_s_);
  ramp_ = ramp;
  const double compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  ++updates_;
  ++interval_updates_;
  interval_compute_s_ += compute_s;
  interval_compute_max_s_ = std::max(interval_compute_max_s_, compute_s);
  const ControlDiagnostics& diagnostics = law_->diagnostics();
  if (diagnostics.nullspace_active) ++interval_nullspace_;
  sigma_max_ = diagnostics.singular_values.max();
  sigma_min_ = diagnostics.singular_values.min();
  error_deg_ = target_->DistanceRad(problem_.s_out_measured) * kRadToDeg;
  condition_ = obeyed_ ? "tracking" : "standby (following the applied φ)";
  if (outcome == ControlIntegrator::Outcome::kRejected) {
    // Never applied; the command repeats the current φ, so the driver (and a lockstep bench)
    // still gets its answer, as `dpc sim` carries the latest command on.
    ++failed_updates_;
    last_rejection_ = fmt::format("update failed: {}", ControlStatusName(status));
  }

  // Built in place: after the first command the message's φ keeps its capacity, so answering
  // a sample allocates nothing.
  if (!last_command_) last_command_.emplace();
  msg::WaveplateCommand& command = *last_command_;
  command.bench_id(settings_.bench_id);
  command.controller_id(settings_.controller_id);
  command.priority(settings_.priority);
  command.sequence_number(++sequence_);
  command.answers_sample(sample.sequence_number());
  command.sample_time_ns(sample.sample_time_ns());
  command.sample_publish_time_ns(sample.publish_time_ns());
  const ControlVector& phi = integrator_->phi();
  command.phi().assign(phi.data(), phi.data() + phi.size());
  if (ramp) {
    command.phi_rate_per_s().assign(rate_.data(), rate_.data() + rate_.size());
    rate_time_ns_ = t_ns;
  } else {
    command.phi_rate_per_s().clear();
  }
  command.publish_time_ns(wall_ns);
  last_answered_sample_ = sample.sequence_number();
  return &command;
}

msg::ControllerStatus ControllerCore::TakeStatus(int64_t now_ns, int64_t wall_ns,
                                                 uint64_t missed_deadlines) {
  if (configured() && last_sample_ns_ != 0 &&
      now_ns - last_sample_ns_ > static_cast<int64_t>(settings_.freeze_after_s * 1e9)) {
    condition_ = fmt::format("frozen: no sample for {:.0f} ms",
                             static_cast<double>(now_ns - last_sample_ns_) * 1e-6);
  } else if (configured() && last_sample_ns_ == 0) {
    condition_ = "waiting for samples";
  }
  std::string condition = condition_;
  if (compensator_ && configured()) {
    if (ramp_) {
      condition += fmt::format(" (ramping with the input at {:.0f} rad/s)",
                               compensator_->predictor().RateRadPerS());
    } else {
      condition += fmt::format(" (predicting {:.3f} ms ahead, input at {:.0f} rad/s)", horizon_s_ * 1e3,
                               compensator_->predictor().RateRadPerS());
    }
  }
  msg::ControllerStatus status;
  status.bench_id(settings_.bench_id);
  status.controller_id(settings_.controller_id);
  status.priority(settings_.priority);
  status.law(law_name_);
  status.obeyed(obeyed_);
  status.condition(condition.substr(0, 127));
  status.answers_sample(last_answered_sample_);
  status.error_deg(error_deg_);
  status.sigma_max(sigma_max_);
  status.sigma_min(sigma_min_);
  status.nullspace_active_fraction(
      interval_updates_ ? static_cast<double>(interval_nullspace_) / static_cast<double>(interval_updates_) : 0.0);
  status.compute_time_mean_s(interval_updates_ ? interval_compute_s_ / static_cast<double>(interval_updates_) : 0.0);
  status.compute_time_max_s(interval_compute_max_s_);
  status.updates(updates_);
  status.failed_updates(failed_updates_);
  status.rejected_samples(rejected_samples_);
  status.missed_deadlines(missed_deadlines);
  status.last_rejection(last_rejection_.substr(0, 255));
  status.publish_time_ns(wall_ns);
  interval_updates_ = interval_nullspace_ = 0;
  interval_compute_s_ = interval_compute_max_s_ = 0.0;
  return status;
}

}  // namespace dpc::services
