#include "driver_core.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"

namespace dpc::services {
namespace {

/// a + b, saturated at the ends of int64 (a command's times are not trusted to be sane).
int64_t SaturatingAdd(int64_t a, int64_t b) {
  int64_t sum;
  if (!__builtin_add_overflow(a, b, &sum)) return sum;
  return b > 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
}

/// Seconds as nanoseconds, for a non-negative duration; saturated (a huge or infinite duration
/// is "forever").
int64_t DurationNs(double seconds) {
  const double ns = seconds * 1e9;
  return ns >= 9e18 ? std::numeric_limits<int64_t>::max() : static_cast<int64_t>(std::max(0.0, ns));
}

}  // namespace

DriverCore::DriverCore(std::vector<StageConfig> stages, DriverSettings settings,
                       WaveplateBackend* backend)
    : chain_(BuildChain(stages)),
      settings_(std::move(settings)),
      backend_(backend),
      arbiter_(ControllerArbiter::Settings{settings_.min_silence_s, settings_.silence_intervals}),
      applied_(backend->Applied()) {
  if (applied_.rate_per_s.size() != applied_.phi.size()) {
    applied_.rate_per_s = ControlVector::Zero(applied_.phi.size());
  }
  // The bounds every command meets: the device's own, narrowed by the scenario's stage ranges
  // and the --max-slew-per-s option, never widened.
  const DeviceLimits device = backend_->limits();
  if (!(device.max_abs_phi > 0.0 && std::isfinite(device.max_abs_phi) && device.max_slew_per_s > 0.0 &&
        std::isfinite(device.max_slew_per_s))) {
    throw std::invalid_argument(fmt::format("backend {}: device limits must be finite and positive "
                                            "(max_abs_phi {}, max_slew_per_s {})",
                                            backend_->name(), device.max_abs_phi, device.max_slew_per_s));
  }
  for (const ControlChannel& control : chain_.controls()) {
    ControlRange range{-device.max_abs_phi, device.max_abs_phi};
    if (control.range) {
      range.min = std::max(range.min, control.range->min);
      range.max = std::min(range.max, control.range->max);
    }
    ranges_.push_back(range);
  }
  max_slew_per_s_ = settings_.max_slew_per_s > 0.0 ? std::min(settings_.max_slew_per_s, device.max_slew_per_s)
                                                     : device.max_slew_per_s;
}

bool DriverCore::OnSample(uint64_t sequence, int64_t sample_time_ns, int64_t publish_time_ns) {
  if (!timeline_.OnSample(sequence, sample_time_ns, publish_time_ns)) return false;
  arbiter_.OnBenchRestart();  // a new bench run numbers its samples from 1 again
  newest_answered_ = 0;
  stand_in_.reset();
  return true;
}

void DriverCore::StopMotion() {
  if (!applied_.moving) return;
  if (backend_->Apply(applied_.Stopped()).empty()) applied_ = backend_->Applied();
}

void DriverCore::Answer(uint64_t sample_number, int64_t wall_ns) {
  // The sample's times from the bench's own record, not from the command.
  answers_sample_ = sample_number;
  newest_answered_ = std::max(newest_answered_, sample_number);
  const std::optional<SampleTimeline::Sample> sample = timeline_.Find(answers_sample_);
  sample_time_ns_ = sample ? sample->time_ns : timeline_.TimeOfNs(answers_sample_);
  sample_publish_time_ns_ = sample ? sample->publish_time_ns : 0;
  command_receive_time_ns_ = wall_ns;
}

void DriverCore::Reject(const std::string& controller_id, const std::string& reason) {
  ++rejected_;
  last_rejection_ = fmt::format("from {}: {}", controller_id.empty() ? "?" : controller_id, reason);
}

std::optional<DriverState> DriverCore::OnMalformedCommand(const std::string& controller_id,
                                                          uint64_t answers_sample, const std::string& reason,
                                                          int64_t wall_ns) {
  Reject(controller_id, reason);
  if (controller_id != arbiter_.obeyed() || !timeline_.CheckSequence(answers_sample).empty()) {
    return std::nullopt;
  }
  // The obeyed controller's bad command: keep φ, but answer the sample (a lockstep bench waits
  // for it) and say why nothing changed.
  Answer(answers_sample, wall_ns);
  saturated_.fill(false);
  return Publishable(wall_ns);
}

std::optional<DriverState> DriverCore::OnCommand(const ControllerCommand& command, int64_t now_ns,
                                                 int64_t wall_ns) {
  const std::string& id = command.controller_id;
  if (std::string reason = timeline_.CheckAnswer(command.answers_sample, command.sample_time_ns);
      !reason.empty()) {
    // Not answered: the sample it names is not one the bench published.
    Reject(id, reason);
    return std::nullopt;
  }

  switch (arbiter_.OnCommand(id, command.priority, command.answers_sample, now_ns)) {
    case ControllerArbiter::Verdict::kRefuse:
      Reject(id, fmt::format("{} controllers already on this bench", ControllerArbiter::kMaxControllers));
      return std::nullopt;
    case ControllerArbiter::Verdict::kIgnore:
      KeepStandbyCommand(command, wall_ns);
      return ConsiderStandIn(command, now_ns, wall_ns);
    case ControllerArbiter::Verdict::kAnswerOnly:
      KeepStandbyCommand(command, wall_ns);
      Answer(command.answers_sample, wall_ns);
      return Publishable(wall_ns);
    case ControllerArbiter::Verdict::kObey:
      break;
  }
  standby_commands_.erase(id);
  if (stand_in_ && stand_in_->answer.command.answers_sample <= command.answers_sample) stand_in_.reset();
  // A stand-in answered a newer sample: this late answer would move the waveplates back.
  if (command.answers_sample < newest_answered_) return std::nullopt;
  return Apply(command, now_ns, wall_ns);
}

bool DriverCore::ObeyedOwes(uint64_t sample) const {
  return !arbiter_.holding() && sample > newest_answered_ && arbiter_.LastAnswered(arbiter_.obeyed()) < sample;
}

DriverState DriverCore::ApplyStandIn(const Received& answer, int64_t now_ns) {
  ++stand_ins_;
  return Apply(answer.command, now_ns, answer.wall_ns);
}

std::optional<DriverState> DriverCore::ConsiderStandIn(const ControllerCommand& command, int64_t now_ns,
                                                       int64_t wall_ns) {
  const uint64_t sample = command.answers_sample;
  if (!ObeyedOwes(sample)) return std::nullopt;
  if (!stand_in_) {
    stand_in_ = StandIn{Received{command, wall_ns}, now_ns + arbiter_.StandInWaitNs()};
    return std::nullopt;
  }
  // The newest answer stands in when the wait for the oldest one the obeyed controller owes is
  // over (the wait does not start again with every sample).
  const ControllerCommand& kept = stand_in_->answer.command;
  if (kept.answers_sample > sample || (kept.answers_sample == sample && kept.priority >= command.priority)) {
    return std::nullopt;
  }
  if (now_ns >= stand_in_->due_ns) {
    stand_in_.reset();
    return ApplyStandIn(Received{command, wall_ns}, now_ns);
  }
  stand_in_->answer = Received{command, wall_ns};
  return std::nullopt;
}

void DriverCore::KeepStandbyCommand(const ControllerCommand& command, int64_t wall_ns) {
  if (standby_commands_.size() >= ControllerArbiter::kMaxControllers &&
      !standby_commands_.count(command.controller_id)) {
    standby_commands_.clear();  // only the controllers that still send come back
  }
  standby_commands_[command.controller_id] = Received{command, wall_ns};
}

DriverState DriverCore::Apply(const ControllerCommand& command, int64_t now_ns, int64_t received_wall_ns) {
  const std::string& id = command.controller_id;
  // Apply: clamp to the ranges, then limit the slew over the driver's own time since the last
  // applied command (never the command's timestamps), from where the current motion has the
  // waveplates at this command's time.
  const int n = chain_.control_count();
  const int64_t start_ns = timeline_.TimeOfNs(command.answers_sample);
  WaveplateMotion motion = applied_;
  applied_.At(start_ns, &motion.phi);
  const ControlVector base = motion.phi;
  bool limited = false;
  const double max_step =
      applied_any_ ? max_slew_per_s_ * static_cast<double>(std::max<int64_t>(0, now_ns - last_applied_ns_)) * 1e-9
                   : INFINITY;
  const bool has_rate = command.rate_per_s.size() != 0;
  const int64_t max_ramp_ns = DurationNs(settings_.max_ramp_s);
  int64_t end_ns = SaturatingAdd(start_ns, max_ramp_ns);
  bool moving = false;
  for (int i = 0; i < n; ++i) {
    const double wanted = command.phi[i];
    const ControlRange& range = ranges_[static_cast<size_t>(i)];
    double value = range.Clamp(wanted);
    value = std::clamp(value, base[i] - max_step, base[i] + max_step);
    const double wanted_rate = has_rate ? command.rate_per_s[i] : 0.0;
    double rate = std::clamp(wanted_rate, -max_slew_per_s_, max_slew_per_s_);
    if (rate != 0.0) {
      // The ramp stops when the first stage reaches its range end; one already there gets none.
      const double room = rate > 0.0 ? range.max - value : value - range.min;
      if (room <= 0.0) {
        rate = 0.0;
      } else if (const int64_t room_ns = DurationNs(room / std::abs(rate)); room_ns < max_ramp_ns) {
        end_ns = std::min(end_ns, SaturatingAdd(start_ns, room_ns));
      }
    }
    const bool clipped = value != wanted || rate != wanted_rate;
    saturated_[static_cast<size_t>(i)] = clipped;
    limited = limited || clipped;
    motion.phi[i] = value;
    motion.rate_per_s[i] = rate;
    moving = moving || rate != 0.0;
  }
  motion.start_ns = start_ns;
  motion.end_ns = std::max(start_ns, end_ns);
  motion.moving = moving && motion.end_ns > start_ns;
  if (std::string failure = backend_->Apply(motion); !failure.empty()) {
    Reject(id, fmt::format("backend {} failed: {}", backend_->name(), failure));
    arbiter_.Hold(fmt::format("holding: backend {} failed: {}", backend_->name(), failure));
    StopMotion();
    return Publishable(received_wall_ns);
  }
  applied_ = backend_->Applied();
  applied_by_ = id;
  applied_any_ = true;
  last_applied_ns_ = now_ns;
  ++applied_count_;
  if (limited) ++limited_;
  Answer(command.answers_sample, received_wall_ns);
  return Publishable(received_wall_ns);
}

std::optional<DriverState> DriverCore::Tick(int64_t now_ns, int64_t wall_ns) {
  // A device that cannot be driven (disconnected, silent, answering garbage): hold the last
  // good φ at once and say why, rather than at the next command.
  if (!arbiter_.holding()) {
    if (std::string fault = backend_->fault(); !fault.empty()) {
      arbiter_.Hold(fmt::format("holding: backend {} failed: {}", backend_->name(), fault));
      saturated_.fill(false);
      StopMotion();
      return Publishable(wall_ns);
    }
  }
  if (stand_in_ && now_ns >= stand_in_->due_ns) {
    // The obeyed controller still owes the sample: the standby's answer stands in.
    const Received answer = stand_in_->answer;
    stand_in_.reset();
    if (ObeyedOwes(answer.command.answers_sample) && timeline_.Find(answer.command.answers_sample)) {
      return ApplyStandIn(answer, now_ns);
    }
  }
  if (!arbiter_.holding()) {
    if (!arbiter_.Check(now_ns)) return std::nullopt;
    // The obeyed controller fell silent: another one is obeyed, or the driver holds.
    saturated_.fill(false);
    if (arbiter_.holding()) {
      StopMotion();
      return Publishable(wall_ns);
    }
    // Failover: the new controller's latest command is applied now, not at its next one (a
    // sample period later), if it answers a sample the bench still knows.
    stand_in_.reset();
    const auto latest = standby_commands_.find(arbiter_.obeyed());
    if (latest != standby_commands_.end() && latest->second.command.answers_sample > newest_answered_ &&
        timeline_.Find(latest->second.command.answers_sample)) {
      const Received received = latest->second;
      standby_commands_.erase(latest);
      return Apply(received.command, now_ns, received.wall_ns);
    }
    return Publishable(wall_ns);
  }
  // Holding: a controller that became alive is obeyed on its next command; the heartbeat keeps
  // the state topic within its deadline and tells late joiners the applied φ.
  if (static_cast<double>(now_ns - last_state_ns_) >= settings_.holding_state_period_s * 1e9) {
    last_state_ns_ = now_ns;
    return Publishable(wall_ns);
  }
  return std::nullopt;
}

int64_t DriverCore::NextTickNs() const {
  if (!arbiter_.holding()) {
    return stand_in_ ? std::min(stand_in_->due_ns, arbiter_.NextCheckNs()) : arbiter_.NextCheckNs();
  }
  return last_state_ns_ + static_cast<int64_t>(settings_.holding_state_period_s * 1e9);
}

DriverState DriverCore::State(int64_t wall_ns) const {
  DriverState state;
  state.sequence = sequence_;
  state.answers_sample = answers_sample_;
  state.sample_time_ns = sample_time_ns_;
  state.sample_publish_time_ns = sample_publish_time_ns_;
  state.command_receive_time_ns = command_receive_time_ns_;
  state.publish_time_ns = wall_ns;
  state.motion = applied_;
  state.saturated = saturated_;
  state.mode = arbiter_.holding() ? DriverMode::kHolding : DriverMode::kActive;
  state.reason = arbiter_.reason();
  static constexpr std::string_view kHolding = "holding: ";
  if (arbiter_.holding() && controllers_connected_ == 0 && arbiter_.switches() > 0 &&
      state.reason.rfind(kHolding, 0) == 0) {
    // The obeyed controller went silent and no controller is left on the bus (it stopped,
    // crashed and its lease ran out, or its host is gone): not a hiccup to wait out.
    state.reason = fmt::format("holding: no controller connected any more (at the hold: {})",
                               state.reason.substr(kHolding.size()));
  }
  state.obeyed_controller_id = arbiter_.obeyed();
  state.obeyed_priority = arbiter_.obeyed_priority();
  state.commands_applied = applied_count_;
  state.commands_rejected = rejected_;
  state.commands_limited = limited_;
  state.controller_switches = arbiter_.switches();
  state.last_rejection = last_rejection_;
  state.applied_controller_id = applied_by_;
  state.stand_ins = stand_ins_;
  return state;
}

DriverState DriverCore::Publishable(int64_t wall_ns) {
  ++sequence_;
  return State(wall_ns);
}

}  // namespace dpc::services
