#include "controller_arbiter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace dpc::services {
namespace {

constexpr double kIntervalSmoothing = 0.05;  ///< weight of a new interval in the average

}  // namespace

ControllerArbiter::ControllerArbiter(Settings settings) : settings_(settings) {}

int64_t ControllerArbiter::SilenceTimeoutNs(const Record& record) const {
  const double floor_ns = settings_.min_silence_s * 1e9;
  return static_cast<int64_t>(std::max(floor_ns, settings_.silence_intervals * record.mean_interval_ns));
}

ControllerArbiter::Liveness ControllerArbiter::Judge(const Record& record, int64_t now_ns) const {
  if (record.commands == 0) return Liveness::kSilent;
  // Others answered newer samples while it said nothing for the grace: dead. (Not while it
  // answers: a controller one sample behind all the time answers every sample.)
  if (Lag(record) > 0 && now_ns >= BehindDueNs(record)) return Liveness::kBehind;
  if (now_ns - record.last_command_ns <= SilenceTimeoutNs(record)) return Liveness::kAlive;
  return Lag(record) == 0 ? Liveness::kSilent : Liveness::kAlive;
}

int64_t ControllerArbiter::BehindGraceNs(const Record& record) const {
  return static_cast<int64_t>(std::max(settings_.min_silence_s * 1e9, kBehindGraceIntervals * record.mean_interval_ns));
}

int64_t ControllerArbiter::BehindDueNs(const Record& record) const {
  return std::max(BehindSinceNs(record), record.last_command_ns) + BehindGraceNs(record);
}

void ControllerArbiter::NoteLateness(Record* record, uint64_t answers_sample, int64_t now_ns) const {
  // Behind the sample's first answer (0 if this is the first); a sample too old to remember
  // says nothing.
  double lateness_ns = 0.0;
  if (answers_sample <= newest_answered_) {
    const FirstAnswer& entry = first_answers_[answers_sample % kAnswerRing];
    if (entry.sample != answers_sample) return;
    lateness_ns = static_cast<double>(std::max<int64_t>(0, now_ns - entry.time_ns));
  }
  const double deviation_ns = std::abs(lateness_ns - record->lateness_mean_ns);
  record->lateness_mean_ns += kIntervalSmoothing * (lateness_ns - record->lateness_mean_ns);
  record->lateness_deviation_ns += kIntervalSmoothing * (deviation_ns - record->lateness_deviation_ns);
}

uint64_t ControllerArbiter::LastAnswered(const std::string& id) const {
  const auto found = controllers_.find(id);
  return found == controllers_.end() ? 0 : found->second.last_answered;
}

int64_t ControllerArbiter::StandInWaitNs() const {
  if (obeyed_.empty()) return 0;
  const Record& record = controllers_.at(obeyed_);
  const double wait_ns =
      record.lateness_mean_ns + kStandInDeviations * record.lateness_deviation_ns + kStandInMarginNs;
  const int64_t longest_ns = std::max(kMinStandInWaitNs, std::min(kMaxStandInWaitNs, BehindGraceNs(record) / 2));
  return std::clamp(static_cast<int64_t>(std::min(wait_ns, 9e18)), kMinStandInWaitNs, longest_ns);
}

int64_t ControllerArbiter::BehindSinceNs(const Record& record) const {
  const uint64_t missed = record.last_answered + 1;
  const FirstAnswer& entry = first_answers_[missed % kAnswerRing];
  return entry.sample == missed ? entry.time_ns : std::numeric_limits<int64_t>::min() / 2;
}

bool ControllerArbiter::Alive(const Record& record, int64_t now_ns) const {
  return Judge(record, now_ns) == Liveness::kAlive && now_ns - record.last_command_ns <= SilenceTimeoutNs(record);
}

std::string ControllerArbiter::DescribeBehind(const std::string& id, const Record& record, int64_t now_ns) const {
  return fmt::format("{} silent for {:.2f} ms, {} samples behind", id,
                     static_cast<double>(now_ns - record.last_command_ns) * 1e-6, Lag(record));
}

void ControllerArbiter::NoteAnswer(Record* record, uint64_t answers_sample, int64_t now_ns) {
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

void ControllerArbiter::OnBenchRestart() {
  newest_answered_ = 0;
  for (auto& [id, record] : controllers_) record.last_answered = 0;
  first_answers_.fill(FirstAnswer{});
}

std::string ControllerArbiter::BestAlive(int64_t now_ns, const std::string& excluded) const {
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

void ControllerArbiter::Obey(const std::string& id, std::string reason) {
  if (id != obeyed_) ++switches_;
  obeyed_ = id;
  reason_ = std::move(reason);
}

void ControllerArbiter::Hold(std::string reason) {
  obeyed_.clear();
  reason_ = std::move(reason);
}

int32_t ControllerArbiter::obeyed_priority() const {
  return obeyed_.empty() ? 0 : controllers_.at(obeyed_).priority;
}

ControllerArbiter::Record* ControllerArbiter::RecordOf(const std::string& id, int64_t now_ns) {
  auto found = controllers_.find(id);
  if (found != controllers_.end()) return &found->second;
  if (controllers_.size() >= kMaxControllers) {
    // Room only in place of a controller that is neither obeyed nor alive.
    auto victim = controllers_.end();
    for (auto it = controllers_.begin(); it != controllers_.end(); ++it) {
      if (it->first == obeyed_ || it->first == suspended_ || Alive(it->second, now_ns)) continue;
      if (victim == controllers_.end() || it->second.last_command_ns < victim->second.last_command_ns) victim = it;
    }
    if (victim == controllers_.end()) return nullptr;
    controllers_.erase(victim);
  }
  return &controllers_.emplace(id, Record{}).first->second;
}

ControllerArbiter::Verdict ControllerArbiter::OnCommand(const std::string& id, int32_t priority,
                                                        uint64_t answers_sample, int64_t now_ns) {
  Record* found = RecordOf(id, now_ns);
  if (found == nullptr) {
    ++refused_;
    return Verdict::kRefuse;
  }
  Record& record = *found;
  if (record.commands > 0) {
    const double interval = static_cast<double>(now_ns - record.last_command_ns);
    record.mean_interval_ns = record.commands == 1 ? interval
                                                   : (1.0 - kIntervalSmoothing) * record.mean_interval_ns +
                                                         kIntervalSmoothing * interval;
  }
  record.priority = priority;
  record.last_command_ns = now_ns;
  ++record.commands;
  NoteLateness(&record, answers_sample, now_ns);
  NoteAnswer(&record, answers_sample, now_ns);
  if (id == obeyed_) return Verdict::kObey;

  // The controller in charge: the obeyed one, or while holding after a general silence the
  // one obeyed before it, which keeps its place unless it fell behind.
  const std::string& holder = obeyed_.empty() ? suspended_ : obeyed_;
  const auto current = holder == id ? controllers_.end() : controllers_.find(holder);
  // Judged by the others' answers, not by the time since its last command alone: after a
  // stall of this driver or of the bench, a standby's queued command may come first.
  const bool current_alive = current != controllers_.end() &&
                             (obeyed_.empty() ? Judge(current->second, now_ns) != Liveness::kBehind
                                              : Judge(current->second, now_ns) == Liveness::kAlive);
  if (current_alive && current->second.priority >= record.priority) {
    return obeyed_.empty() ? Verdict::kAnswerOnly : Verdict::kIgnore;
  }
  std::string reason = fmt::format("obeying {} (priority {})", id, record.priority);
  if (current_alive) {
    reason = fmt::format("obeying {} (priority {} over {})", id, record.priority, holder);
  } else if (current != controllers_.end()) {
    reason += ": " + DescribeBehind(holder, current->second, now_ns);
  }
  suspended_.clear();
  Obey(id, std::move(reason));
  return Verdict::kObey;
}

bool ControllerArbiter::Check(int64_t now_ns) {
  if (obeyed_.empty()) return false;
  const Record& record = controllers_.at(obeyed_);
  const Liveness liveness = Judge(record, now_ns);
  if (liveness == Liveness::kAlive) return false;
  const std::string silent = obeyed_;
  if (liveness == Liveness::kSilent) {
    // Nobody answered anything newer: no samples, or the whole machine stalled. Not this
    // controller's failure: hold, and give it back control first when commands resume.
    const double silent_ms = static_cast<double>(now_ns - record.last_command_ns) * 1e-6;
    Hold(fmt::format("holding: {} silent for {:.2f} ms and no other controller answered newer samples; "
                     "{} gets control back first",
                     silent, silent_ms, silent));
    suspended_ = silent;
    return true;
  }
  const std::string next = BestAlive(now_ns, silent);
  const std::string behind = DescribeBehind(silent, record, now_ns);
  if (!next.empty()) {
    Obey(next, fmt::format("obeying {} (priority {}): {}", next, controllers_.at(next).priority, behind));
  } else {
    Hold(fmt::format("holding: {}, no other controller", behind));
  }
  return true;
}

int64_t ControllerArbiter::NextCheckNs() const {
  if (obeyed_.empty()) return std::numeric_limits<int64_t>::max();
  const Record& record = controllers_.at(obeyed_);
  const int64_t silent_due_ns = record.last_command_ns + SilenceTimeoutNs(record) + 1;
  if (Lag(record) == 0) return silent_due_ns;
  return BehindDueNs(record);  // silent but behind: alive until then
}

}  // namespace dpc::services
