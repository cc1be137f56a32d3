#include "controller_core.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::services {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
}

ControllerCore::ControllerCore(ControllerSettings settings) : settings_(std::move(settings)) {
  law_name_ = std::string(MethodName(settings_.controller.method));
}

ControllerCore::~ControllerCore() = default;

std::string ControllerCore::OnDevice(const DeviceDescription& description) {
  try {
    const std::vector<StageConfig>& stages = description.stages;
    const int controls = ScenarioControlCount(stages);
    // The law must fit the device and the current target (inverse needs a square task).
    TargetConfig target_config;
    if (target_) {
      target_config.kind = target_->is_point() ? TargetConfig::Kind::kPoint : TargetConfig::Kind::kSet;
    }
    ValidateControllerConfig(settings_.controller, controls, target_config, settings_.simulation);
    // The driver's stages decide: a range criterion without a range (or a gpt threshold no
    // range lets the controls reach) would run silently as something else.
    ValidateControllerForStages(settings_.controller, stages);
    auto chain = std::make_unique<WaveplateChain>(BuildChain(stages));
    controller_.reset();
    chain_ = std::move(chain);
    applied_phi_ = ControlVector::Zero(controls);
    applied_motion_.phi = ControlVector::Zero(controls);
    applied_motion_.rate_per_s = ControlVector::Zero(controls);
    applied_motion_.moving = false;
    rate_time_ns_ = 0;
    ramp_ = false;
    device_max_ramp_s_ = description.max_ramp_s;
    have_state_ = false;
    latency_estimate_s_ = -1.0;
    if (target_) BuildController();
    condition_ = target_ ? "waiting for the driver's state" : "waiting for the target";
    return {};
  } catch (const std::exception& e) {
    condition_ = fmt::format("unusable device description: {}", e.what());
    return condition_;
  }
}

void ControllerCore::OnUnusableDevice(const std::string& reason) {
  condition_ = fmt::format("unusable device description: {}", reason);
}

void ControllerCore::OnUnusableTarget(const std::string& reason) {
  condition_ = fmt::format("unusable target: {}", reason);
}

std::string ControllerCore::OnTarget(const BenchTarget& message) {
  if (message.revision <= target_revision_ && target_) return {};  // already have it
  try {
    auto target = std::make_unique<Target>(BuildTarget(message.target));
    if (controller_) controller_->SetTarget(*target);  // throws if the law does not fit
    target_ = std::move(target);
    target_revision_ = message.revision;
    if (chain_ && !controller_) BuildController();
    if (!chain_) condition_ = "waiting for the device description";
    else if (!have_state_) condition_ = "waiting for the driver's state";
    return {};
  } catch (const std::exception& e) {
    condition_ = fmt::format("unusable target: {}", e.what());
    return condition_;
  }
}

void ControllerCore::BuildController() {
  controller_ = std::make_unique<PolarizationController>(*chain_, *target_, settings_.controller,
                                                         BuildLawTiming(settings_.simulation),
                                                         applied_phi_);
}

void ControllerCore::Resync(const ControlVector& phi) {
  if (controller_) controller_->Reset(phi);
}

void ControllerCore::OnState(const DriverState& state) {
  if (!chain_ || state.control_count() != chain_->control_count()) return;
  applied_motion_ = state.motion;
  applied_motion_.At(last_sample_time_ns_, &applied_phi_);
  const bool first = !have_state_;
  have_state_ = true;
  obeyed_ = state.mode == DriverMode::kActive && state.obeyed_controller_id == settings_.controller_id;
  if (first) {
    Resync(applied_phi_);
    return;
  }
  if (obeyed_) {
    state_answers_sample_ = state.answers_sample;
    if (state.answers_sample == last_answered_sample_ && state.any_saturated()) {
      Resync(applied_phi_);  // the driver clamped our latest command: no wind-up
    }
    return;
  }
  // Not obeyed: follow what is applied, so that the first obeyed command continues from there.
  // One exception keeps a lockstep run exact: a holding heartbeat the driver sent before it saw
  // our latest command (it answers an older sample) must not undo that command. In real time
  // such a race costs at most one step, and following every heartbeat matters more (a
  // controller whose commands have not reached the driver yet must not drift on its own).
  const bool stale_heartbeat = state.mode == DriverMode::kHolding && lockstep_ &&
                               state.answers_sample < last_answered_sample_;
  if (!stale_heartbeat) Resync(applied_phi_);
}

double ControllerCore::PredictionHorizonS(const BenchSample& sample) {
  const PredictionConfig& prediction = *settings_.controller.prediction;
  const double period_s = 1.0 / settings_.simulation.sample_rate_hz;
  if (prediction.horizon_samples) return *prediction.horizon_samples * period_s;
  if (sample.lockstep) return settings_.simulation.delay_s;  // the simulated bench's own delay
  const auto& [sequence, time_ns] = sample_times_ns_[state_answers_sample_ % kSampleTimeRing];
  if (obeyed_ && state_answers_sample_ != 0 && sequence == state_answers_sample_) {
    const double latency_s = static_cast<double>(sample.time_ns - time_ns) * 1e-9;
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

void ControllerCore::RejectInput(std::string reason) {
  ++rejected_samples_;
  last_rejection_ = std::move(reason);
}

const ControllerCommand* ControllerCore::OnSample(const BenchSample& sample, int64_t now_ns,
                                                 int64_t wall_ns) {
  if (!configured()) return nullptr;
  if (sample.sequence == last_sample_ && last_command_ && last_command_->answers_sample == last_sample_) {
    // The same sample again: a lockstep bench re-publishes when its answer was lost (the
    // periodic topics are best effort). Answer it again, without integrating twice.
    last_command_->publish_time_ns = wall_ns;
    return &*last_command_;
  }
  if (sample.sequence <= last_sample_) {
    // Out of order or repeated (a restarted bench starts again at 1: accept after a gap).
    if (now_ns - last_sample_ns_ < static_cast<int64_t>(settings_.freeze_after_s * 1e9)) return nullptr;
  }
  if (last_sample_ns_ != 0 &&
      now_ns - last_sample_ns_ > static_cast<int64_t>(settings_.freeze_after_s * 1e9)) {
    Resync(applied_phi_);  // samples resume after a gap: re-join from what is applied
    controller_->ForgetInput();  // the input's history is stale
  }
  last_sample_ = sample.sequence;
  last_sample_ns_ = now_ns;
  lockstep_ = sample.lockstep;
  const int64_t t_ns = sample.time_ns;
  last_sample_time_ns_ = t_ns;
  // Ramp mode needs a driver that ramps; otherwise a predicting controller aims at a point.
  const bool ramp = predicting() && !lockstep_ && device_max_ramp_s_ > 0.0 &&
                    settings_.prediction_mode == PredictionMode::kRamp;
  if (applied_motion_.moving) {
    applied_motion_.At(t_ns, &applied_phi_);
    if (!obeyed_) Resync(applied_phi_);  // standby: follow the motion where it is now
  }
  if (obeyed_ && ramp && ramp_ && rate_time_ns_ != 0) {
    // The waveplates moved along the latest command's ramp since its sample: so does φ.
    controller_->AdvanceAlongRate(
        std::clamp(static_cast<double>(t_ns - rate_time_ns_) * 1e-9, 0.0, device_max_ramp_s_));
  }

  const auto start = std::chrono::steady_clock::now();
  ControlInput input;
  input.s_in = sample.s_in;
  input.s_out = sample.s_out;
  if (predicting()) {
    sample_times_ns_[sample.sequence % kSampleTimeRing] = {sample.sequence, t_ns};
    horizon_s_ = PredictionHorizonS(sample);
    input.time_ns = t_ns;
    input.horizon_s = horizon_s_;
    input.rate_command = ramp;
  }
  const ControlUpdate update = controller_->Update(input);
  ramp_ = ramp;
  const double compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  ++updates_;
  ++interval_updates_;
  interval_compute_s_ += compute_s;
  interval_compute_max_s_ = std::max(interval_compute_max_s_, compute_s);
  const ControlDiagnostics& diagnostics = controller_->diagnostics();
  if (diagnostics.nullspace_active) ++interval_nullspace_;
  sigma_max_ = diagnostics.singular_values.max();
  sigma_min_ = diagnostics.singular_values.min();
  error_deg_ = target_->DistanceRad(input.s_out) * kRadToDeg;
  condition_ = obeyed_ ? "tracking" : "standby (following the applied φ)";
  if (update.outcome == ControlIntegrator::Outcome::kRejected) {
    // Never applied; the command repeats the current φ, so the driver (and a lockstep bench)
    // still gets its answer, as `dpc sim` carries the latest command on.
    ++failed_updates_;
    last_rejection_ = fmt::format("update failed: {}", ControlStatusName(update.status));
  }

  // Built in place: the command's vectors have fixed capacity, so answering a sample
  // allocates nothing.
  if (!last_command_) {
    last_command_.emplace();
    last_command_->controller_id = settings_.controller_id;
    last_command_->priority = settings_.priority;
  }
  ControllerCommand& command = *last_command_;
  command.sequence = ++sequence_;
  command.answers_sample = sample.sequence;
  command.sample_time_ns = sample.time_ns;
  command.sample_publish_time_ns = sample.publish_time_ns;
  command.phi = controller_->phi();
  if (ramp) {
    command.rate_per_s = controller_->rate_per_s();
    rate_time_ns_ = t_ns;
  } else {
    command.rate_per_s.resize(0);
  }
  command.publish_time_ns = wall_ns;
  last_answered_sample_ = sample.sequence;
  return &command;
}

ControllerStatusReport ControllerCore::TakeStatus(int64_t now_ns, int64_t wall_ns,
                                                  uint64_t missed_deadlines) {
  if (configured() && last_sample_ns_ != 0 &&
      now_ns - last_sample_ns_ > static_cast<int64_t>(settings_.freeze_after_s * 1e9)) {
    condition_ = fmt::format("frozen: no sample for {:.0f} ms",
                             static_cast<double>(now_ns - last_sample_ns_) * 1e-6);
  } else if (configured() && last_sample_ns_ == 0) {
    condition_ = "waiting for samples";
  }
  std::string condition = condition_;
  if (configured() && predicting()) {
    const double rate_rad_per_s = controller_->compensator()->predictor().RateRadPerS();
    if (ramp_) {
      condition += fmt::format(" (ramping with the input at {:.0f} rad/s)", rate_rad_per_s);
    } else {
      condition += fmt::format(" (predicting {:.3f} ms ahead, input at {:.0f} rad/s)", horizon_s_ * 1e3,
                               rate_rad_per_s);
    }
  }
  ControllerStatusReport status;
  status.controller_id = settings_.controller_id;
  status.priority = settings_.priority;
  status.law = law_name_;
  status.obeyed = obeyed_;
  status.condition = condition;
  status.answers_sample = last_answered_sample_;
  status.error_deg = error_deg_;
  status.sigma_max = sigma_max_;
  status.sigma_min = sigma_min_;
  status.nullspace_active_fraction =
      interval_updates_ ? static_cast<double>(interval_nullspace_) / static_cast<double>(interval_updates_) : 0.0;
  status.compute_time_mean_s = interval_updates_ ? interval_compute_s_ / static_cast<double>(interval_updates_) : 0.0;
  status.compute_time_max_s = interval_compute_max_s_;
  status.updates = updates_;
  status.failed_updates = failed_updates_;
  status.rejected_samples = rejected_samples_;
  status.missed_deadlines = missed_deadlines;
  status.last_rejection = last_rejection_;
  status.publish_time_ns = wall_ns;
  interval_updates_ = interval_nullspace_ = 0;
  interval_compute_s_ = interval_compute_max_s_ = 0.0;
  return status;
}

}  // namespace dpc::services
