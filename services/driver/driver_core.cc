#include "driver_core.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"

namespace dpc::services {
namespace {

constexpr double kIntervalSmoothing = 0.05;   ///< weight of a new interval in the average
constexpr size_t kMaxControllers = 64;        ///< records kept; the longest-silent is dropped

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
  reason_ = "holding: no controller yet";
}

int64_t DriverCore::SilenceTimeoutNs(const ControllerRecord& record) const {
  const double floor_ns = settings_.min_silence_s * 1e9;
  return static_cast<int64_t>(std::max(floor_ns, settings_.silence_intervals * record.mean_interval_ns));
}

DriverCore::Liveness DriverCore::Judge(const ControllerRecord& record, int64_t now_ns) const {
  if (record.commands == 0) return Liveness::kSilent;
  const int64_t timeout_ns = SilenceTimeoutNs(record);
  if (now_ns - record.last_command_ns <= timeout_ns) return Liveness::kAlive;
  if (Lag(record) == 0) return Liveness::kSilent;
  // Silent, and others answered newer samples: dead, unless they only just started again
  // (after a stall of the bench or of this driver, whoever's queued command comes first).
  return now_ns - BehindSinceNs(record) > BehindGraceNs(record) ? Liveness::kBehind : Liveness::kAlive;
}

int64_t DriverCore::BehindGraceNs(const ControllerRecord& record) const {
  return std::max<int64_t>(SilenceTimeoutNs(record) / 4, static_cast<int64_t>(4.0 * record.mean_interval_ns));
}

int64_t DriverCore::BehindSinceNs(const ControllerRecord& record) const {
  const uint64_t missed = record.last_answered + 1;
  const FirstAnswer& entry = first_answers_[missed % kAnswerRing];
  return entry.sample == missed ? entry.time_ns : std::numeric_limits<int64_t>::min() / 2;
}

// A candidate to obey: not behind, and heard from within its timeout.
bool DriverCore::Alive(const ControllerRecord& record, int64_t now_ns) const {
  return Judge(record, now_ns) == Liveness::kAlive &&
         now_ns - record.last_command_ns <= SilenceTimeoutNs(record);
}

std::string DriverCore::DescribeBehind(const std::string& id, const ControllerRecord& record,
                                       int64_t now_ns) const {
  return fmt::format("{} silent for {:.2f} ms, {} samples behind", id,
                     static_cast<double>(now_ns - record.last_command_ns) * 1e-6, Lag(record));
}

void DriverCore::NoteAnswer(ControllerRecord* record, uint64_t answers_sample, int64_t now_ns) {
  record->last_answered = std::max(record->last_answered, answers_sample);
  if (answers_sample <= newest_answered_) return;
  // Samples answered for the first time (usually one; after a gap, every one skipped). At most
  // the ring's worth, counted down from the newest: bounded work and no counter that can wrap,
  // whatever number a command carries.
  const uint64_t fresh = std::min<uint64_t>(answers_sample - newest_answered_, kAnswerRing);
  for (uint64_t i = 0; i < fresh; ++i) {
    const uint64_t sample = answers_sample - i;
    first_answers_[sample % kAnswerRing] = FirstAnswer{sample, now_ns};
  }
  newest_answered_ = answers_sample;
}

bool DriverCore::OnSample(uint64_t sequence, int64_t sample_time_ns, int64_t publish_time_ns) {
  if (!timeline_.OnSample(sequence, sample_time_ns, publish_time_ns)) return false;
  // A new bench run numbers its samples from 1 again: nobody is behind.
  newest_answered_ = 0;
  for (auto& [id, record] : controllers_) record.last_answered = 0;
  first_answers_.fill(FirstAnswer{});
  return true;
}

std::string DriverCore::BestAlive(int64_t now_ns, const std::string& excluded) const {
  std::string best;
  int32_t best_priority = 0;
  for (const auto& [id, record] : controllers_) {
    if (id == excluded || !Alive(record, now_ns)) continue;
    if (best.empty() || record.priority > best_priority) {
      best = id;
      best_priority = record.priority;
    }
  }
  return best;
}

void DriverCore::Obey(const std::string& id, const std::string& reason) {
  if (id != obeyed_) ++switches_;
  obeyed_ = id;
  reason_ = reason;
}

void DriverCore::Hold(const std::string& reason) {
  obeyed_.clear();
  reason_ = reason;
  StopMotion();
}

void DriverCore::StopMotion() {
  if (!applied_.moving) return;
  if (backend_->Apply(applied_.Stopped()).empty()) applied_ = backend_->Applied();
}

void DriverCore::Answer(uint64_t sample_number, int64_t wall_ns) {
  // The sample's times from the bench's own record, not from the command.
  answers_sample_ = sample_number;
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
  if (controller_id != obeyed_ || !timeline_.CheckSequence(answers_sample).empty()) {
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

  // Liveness and priority of this controller.
  auto found = controllers_.find(id);
  if (found == controllers_.end()) {
    if (controllers_.size() >= kMaxControllers) {
      auto oldest = std::min_element(controllers_.begin(), controllers_.end(),
                                     [](const auto& a, const auto& b) {
                                       return a.second.last_command_ns < b.second.last_command_ns;
                                     });
      if (oldest->first != obeyed_) controllers_.erase(oldest);
    }
    found = controllers_.emplace(id, ControllerRecord{}).first;
  }
  ControllerRecord& record = found->second;
  if (record.commands > 0) {
    const double interval = static_cast<double>(now_ns - record.last_command_ns);
    record.mean_interval_ns = record.commands == 1
                                  ? interval
                                  : (1.0 - kIntervalSmoothing) * record.mean_interval_ns +
                                        kIntervalSmoothing * interval;
  }
  record.priority = command.priority;
  record.last_command_ns = now_ns;
  ++record.commands;
  NoteAnswer(&record, command.answers_sample, now_ns);

  if (id != obeyed_) {
    // The controller in charge: the obeyed one, or while holding after a general silence the
    // one obeyed before it, which keeps its place unless it fell behind.
    const std::string& holder = obeyed_.empty() ? suspended_ : obeyed_;
    const auto current = holder == id ? controllers_.end() : controllers_.find(holder);
    // Judged by the others' answers, not by the time since its last command alone: after a
    // stall of this driver or of the bench, a standby's queued command may come first.
    const bool current_alive =
        current != controllers_.end() &&
        (obeyed_.empty() ? Judge(current->second, now_ns) != Liveness::kBehind
                         : Judge(current->second, now_ns) == Liveness::kAlive);
    if (current_alive && current->second.priority >= record.priority) {
      if (!obeyed_.empty()) return std::nullopt;
      // Holding for the suspended controller: answer the sample (a lockstep bench waits for
      // it), apply nothing.
      Answer(command.answers_sample, wall_ns);
      return Publishable(wall_ns);
    }
    std::string reason = fmt::format("obeying {} (priority {})", id, record.priority);
    if (current_alive) {
      reason = fmt::format("obeying {} (priority {} over {})", id, record.priority, holder);
    } else if (current != controllers_.end()) {
      reason += ": " + DescribeBehind(holder, current->second, now_ns);
    }
    suspended_.clear();
    Obey(id, reason);
  }

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
    Hold(fmt::format("holding: backend {} failed: {}", backend_->name(), failure));
    return Publishable(wall_ns);
  }
  applied_ = backend_->Applied();
  applied_any_ = true;
  last_applied_ns_ = now_ns;
  ++applied_count_;
  if (limited) ++limited_;
  Answer(command.answers_sample, wall_ns);
  return Publishable(wall_ns);
}

std::optional<DriverState> DriverCore::Tick(int64_t now_ns, int64_t wall_ns) {
  if (!obeyed_.empty()) {
    const ControllerRecord& record = controllers_.at(obeyed_);
    const Liveness liveness = Judge(record, now_ns);
    if (liveness == Liveness::kAlive) return std::nullopt;
    const std::string silent = obeyed_;
    saturated_.fill(false);
    if (liveness == Liveness::kSilent) {
      const double silent_ms = static_cast<double>(now_ns - record.last_command_ns) * 1e-6;
      // Nobody answered anything newer: no samples, or the whole machine stalled. Not this
      // controller's failure: hold, and give it back control first when commands resume.
      Hold(fmt::format("holding: {} silent for {:.2f} ms and no other controller answered newer samples; "
                       "{} gets control back first",
                       silent, silent_ms, silent));
      suspended_ = silent;
      return Publishable(wall_ns);
    }
    const std::string next = BestAlive(now_ns, silent);
    const std::string behind = DescribeBehind(silent, record, now_ns);
    if (!next.empty()) {
      Obey(next, fmt::format("obeying {} (priority {}): {}", next, controllers_.at(next).priority, behind));
    } else {
      Hold(fmt::format("holding: {}, no other controller", behind));
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
  if (!obeyed_.empty()) {
    const ControllerRecord& record = controllers_.at(obeyed_);
    const int64_t silent_due_ns = record.last_command_ns + SilenceTimeoutNs(record) + 1;
    if (Lag(record) == 0) return silent_due_ns;
    return std::max(silent_due_ns, BehindSinceNs(record) + BehindGraceNs(record) + 1);
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
  state.mode = obeyed_.empty() ? DriverMode::kHolding : DriverMode::kActive;
  state.reason = reason_;
  state.obeyed_controller_id = obeyed_;
  state.obeyed_priority = obeyed_.empty() ? 0 : controllers_.at(obeyed_).priority;
  state.commands_applied = applied_count_;
  state.commands_rejected = rejected_;
  state.commands_limited = limited_;
  state.controller_switches = switches_;
  state.last_rejection = last_rejection_;
  return state;
}

DriverState DriverCore::Publishable(int64_t wall_ns) {
  ++sequence_;
  return State(wall_ns);
}

}  // namespace dpc::services
