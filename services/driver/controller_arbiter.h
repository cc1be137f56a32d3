#pragma once
// Which controller the waveplate driver obeys. Every controller publishes a command for every
// sample; the driver obeys exactly one: the highest-priority controller that is alive (ties:
// the one already obeyed). The obeyed controller is judged by the other controllers' answers
// (each command names the sample it answers) and by its silence:
//   - behind: another controller answered a sample it has not, and it has been silent for the
//     grace since then (grace = max(min_silence_s, 1.5 × its mean command interval), counted
//     from its own last command if that is later): dead. The driver switches to the next alive
//     controller, or holds. Below ~1.2 kHz the grace does not grow with the sample period: a
//     controller killed at 2 kHz is replaced ~1.2 ms after the standby answered the first
//     sample it missed, as at 10 kHz (the DDS deadline, ≥ 10 ms on Fast DDS 2.9, would take
//     about ten times longer); at slower rates the gap stays within ~2.5 periods;
//   - silent: nobody answered anything newer for its silence timeout,
//       timeout = max(min_silence_s, silence_intervals × its mean command interval)
//     (the interval an exponential average of its command arrivals): no samples, or the whole
//     machine stalled; nobody's failure. The driver holds and gives it control back first:
//     until it falls behind as above, another controller's command gets a holding answer (a
//     lockstep bench still advances) instead of control. Without this, whichever command came
//     first after a stall took over, and the primary took back over at once.
// Check() runs when the next such deadline is due (NextCheckNs).
//
// Stand-ins. Between a controller's death and its replacement (the grace above) the driver
// need not go without commands: when another controller answered a sample and the obeyed one
// has not answered it StandInWaitNs() later, the driver applies that answer in its place
// (DriverCore). The wait follows how late the obeyed controller usually answers behind the
// first answer of a sample (an average and its mean deviation), so a primary that is merely
// slower than its standby is not stood in for at every sample.
//
// Bounded: at most kMaxControllers records (a newcomer beyond them is refused while every
// known controller is alive; else the longest-silent record makes room), and the first answers
// of the latest kAnswerRing samples; no number a command carries makes it loop or overflow.

#include <array>
#include <cstdint>
#include <map>
#include <string>

namespace dpc::services {

class ControllerArbiter {
 public:
  struct Settings {
    double min_silence_s = 10e-3;    ///< the grace of a controller behind the others (see above)
    double silence_intervals = 8.0;  ///< a silence of nobody longer than this many intervals: hold
  };
  static constexpr size_t kMaxControllers = 64;
  /// The grace of a controller behind the others, in its command intervals, if longer than
  /// min_silence_s.
  static constexpr double kBehindGraceIntervals = 1.5;
  static constexpr size_t kAnswerRing = 1024;
  /// The stand-in wait: the obeyed controller's usual lateness behind a sample's first answer
  /// plus kStandInDeviations of its mean deviation and a margin, at least kMinStandInWaitNs and
  /// at most kMaxStandInWaitNs or half its behind grace.
  static constexpr int64_t kMinStandInWaitNs = 200'000;
  static constexpr int64_t kMaxStandInWaitNs = 600'000;
  static constexpr int64_t kStandInMarginNs = 100'000;
  static constexpr double kStandInDeviations = 4.0;

  /// What to do with a command.
  enum class Verdict {
    kObey,        ///< the obeyed controller's (perhaps obeyed from this command on): apply it
    kAnswerOnly,  ///< holding for the controller obeyed before a general silence: answer its
                  ///< sample (a lockstep bench waits for it), apply nothing
    kIgnore,      ///< a standby controller's
    kRefuse,      ///< a new controller beyond kMaxControllers while every known one is alive
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
  /// Commands of new controllers refused for want of room (kRefuse).
  uint64_t refused() const { return refused_; }
  /// Why it obeys whom it obeys, or why it holds.
  const std::string& reason() const { return reason_; }
  /// The newest sample `id` answered (0: none, or unknown).
  uint64_t LastAnswered(const std::string& id) const;
  /// How long after another controller's answer the obeyed controller's answer to the same
  /// sample is waited for before the other one stands in (see above); 0 while holding.
  int64_t StandInWaitNs() const;

 private:
  struct Record {
    int32_t priority = 0;
    int64_t last_command_ns = 0;
    double mean_interval_ns = 0.0;    ///< exponential average; 0 until two commands
    uint64_t commands = 0;
    uint64_t last_answered = 0;       ///< the newest sample it answered
    /// How late it answers a sample after the sample's first answer: exponential averages of
    /// the lateness and of its absolute deviation from that average.
    double lateness_mean_ns = 0.0;
    double lateness_deviation_ns = 0.0;
  };
  /// kBehind (dead): another controller answered a sample it has not, and it has been silent
  /// for the grace since then; kSilent: silent for its timeout and nobody answered anything
  /// newer. Otherwise kAlive.
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
  /// When it counts as behind: the grace after the later of BehindSinceNs and its last command.
  int64_t BehindDueNs(const Record& record) const;
  int64_t SilenceTimeoutNs(const Record& record) const;
  int64_t BehindGraceNs(const Record& record) const;
  /// Updates the record's lateness with its answer to `answers_sample` arriving at `now_ns`.
  void NoteLateness(Record* record, uint64_t answers_sample, int64_t now_ns) const;
  /// "<id> silent for X ms, N samples behind".
  std::string DescribeBehind(const std::string& id, const Record& record, int64_t now_ns) const;
  void NoteAnswer(Record* record, uint64_t answers_sample, int64_t now_ns);
  /// The record of `id`, made if new (at the limit, in place of the longest-silent record that
  /// is not alive nor obeyed); nullptr if there is no room.
  Record* RecordOf(const std::string& id, int64_t now_ns);
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
  uint64_t refused_ = 0;
  uint64_t newest_answered_ = 0;     ///< the newest sample any controller answered
  std::array<FirstAnswer, kAnswerRing> first_answers_{};  ///< by sample number modulo the ring
};

}  // namespace dpc::services
