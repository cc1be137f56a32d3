#pragma once
// Which controller the waveplate driver obeys. Every controller publishes a command for every
// sample; the driver obeys exactly one: the highest-priority controller that is alive (ties:
// the one already obeyed). A controller's silence timeout is
//
//   timeout = max(min_silence_s, silence_intervals × its mean command interval)
//
// (the interval is an exponential average of its command arrivals). The obeyed controller is
// judged by its silence and by the other controllers' answers (each command names the sample
// it answers):
//   - silent for its timeout while another controller answered a sample it has not (for
//     longer than a grace: a quarter of the timeout, at least 4 command intervals): dead; the
//     driver switches to the next alive controller, or holds. At 10 kHz a killed controller is
//     noticed ~1.5 ms after its last command, where the DDS deadline (≥ 10 ms on Fast DDS 2.9)
//     would take about ten times longer;
//   - silent for its timeout and nobody answered anything newer: no samples, or the whole
//     machine stalled; nobody's failure. The driver holds and gives it control back first:
//     until it falls behind as above, another controller's command gets a holding answer
//     (a lockstep bench still advances) instead of control. Without this, whichever command
//     came first after a stall took over, and the primary took back over at once.
// Check() runs when the next such deadline is due (NextCheckNs).
//
// Bounded: at most kMaxControllers records (the longest-silent is dropped for a new one), and
// the first answers of the latest kAnswerRing samples; no number a command carries makes it
// loop or overflow.

#include <array>
#include <cstdint>
#include <map>
#include <string>

namespace dpc::services {

class ControllerArbiter {
 public:
  struct Settings {
    double min_silence_s = 1.5e-3;   ///< shortest silence that counts as a dead controller
    double silence_intervals = 8.0;  ///< or this many of its command intervals, if longer
  };
  static constexpr size_t kMaxControllers = 64;
  static constexpr size_t kAnswerRing = 1024;

  /// What to do with a command.
  enum class Verdict {
    kObey,        ///< the obeyed controller's (perhaps obeyed from this command on): apply it
    kAnswerOnly,  ///< holding for the controller obeyed before a general silence: answer its
                  ///< sample (a lockstep bench waits for it), apply nothing
    kIgnore,      ///< a standby controller's
  };

  explicit ControllerArbiter(Settings settings);

  /// A command from `id` with `priority`, answering `answers_sample` (one the bench published),
  /// arrived at `now_ns` (monotonic).
  Verdict OnCommand(const std::string& id, int32_t priority, uint64_t answers_sample, int64_t now_ns);
  /// Judges the obeyed controller at `now_ns`: returns true if it was found dead or silent, and
  /// the arbiter switched to another controller or holds (reason() says why).
  bool Check(int64_t now_ns);
  /// When Check next has something to judge (monotonic ns; INT64_MAX while holding).
  int64_t NextCheckNs() const;
  /// Obeys nobody, for `reason` (e.g. the device failed).
  void Hold(std::string reason);
  /// A new bench run numbers its samples from 1 again: nobody is behind.
  void OnBenchRestart();

  const std::string& obeyed() const { return obeyed_; }
  bool holding() const { return obeyed_.empty(); }
  int32_t obeyed_priority() const;
  uint64_t switches() const { return switches_; }
  /// Why it obeys whom it obeys, or why it holds.
  const std::string& reason() const { return reason_; }

 private:
  struct Record {
    int32_t priority = 0;
    int64_t last_command_ns = 0;
    double mean_interval_ns = 0.0;    ///< exponential average; 0 until two commands
    uint64_t commands = 0;
    uint64_t last_answered = 0;       ///< the newest sample it answered
  };
  /// Silent for longer than its timeout and: kBehind (dead), another controller answered a
  /// sample it has not, longer ago than the grace; kSilent, nobody answered anything newer.
  /// Otherwise kAlive.
  enum class Liveness { kAlive, kBehind, kSilent };
  struct FirstAnswer {
    uint64_t sample = 0;
    int64_t time_ns = 0;
  };

  Liveness Judge(const Record& record, int64_t now_ns) const;
  /// A candidate to obey: not behind, and heard from within its timeout.
  bool Alive(const Record& record, int64_t now_ns) const;
  uint64_t Lag(const Record& record) const { return newest_answered_ - record.last_answered; }
  /// When another controller first answered the oldest sample `record` has not answered (very
  /// long ago if that is too old to remember). Only for Lag(record) > 0.
  int64_t BehindSinceNs(const Record& record) const;
  int64_t BehindGraceNs(const Record& record) const;
  int64_t SilenceTimeoutNs(const Record& record) const;
  /// "<id> silent for X ms, N samples behind".
  std::string DescribeBehind(const std::string& id, const Record& record, int64_t now_ns) const;
  void NoteAnswer(Record* record, uint64_t answers_sample, int64_t now_ns);
  /// The record of `id`, made (and the longest-silent one dropped at the limit) if new.
  Record& RecordOf(const std::string& id);
  /// The best alive controller other than `excluded`, or "" if none.
  std::string BestAlive(int64_t now_ns, const std::string& excluded) const;
  void Obey(const std::string& id, std::string reason);

  Settings settings_;
  std::map<std::string, Record> controllers_;
  std::string obeyed_;               ///< "" while holding
  /// While holding because no command came from anyone: the controller obeyed before; the
  /// arbiter waits for it (others get kAnswerOnly) unless it falls behind.
  std::string suspended_;
  std::string reason_ = "holding: no controller yet";
  uint64_t switches_ = 0;
  uint64_t newest_answered_ = 0;     ///< the newest sample any controller answered
  std::array<FirstAnswer, kAnswerRing> first_answers_{};  ///< by sample number modulo the ring
};

}  // namespace dpc::services
