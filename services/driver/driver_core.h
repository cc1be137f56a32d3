#pragma once
// The waveplate driver's logic, without DDS: which controller to obey, what to apply, what to
// report. The DDS wiring (main.cc) calls it under one lock, with monotonic time in ns.
//
// Arbitration. Every controller publishes a command for every sample; the driver obeys exactly
// one: the highest-priority controller that is alive (ties: the one already obeyed). Its
// silence timeout is
//   timeout = max(min_silence_s, silence_intervals × its mean command interval)
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
//     came first after a stall took over, and the primary took back over at once: on a loaded
//     2-core VM at 10 kHz, 50 needless switches to the standby in 30 s, 25 with it at the same
//     2-ms timeout, 30 at 1.5 ms (the default).
// Tick() runs when the next such deadline is due (at most every 0.25 ms).
//
// Every command is checked (its shape at the service's edge, bus::ReadCommand: stage count,
// NaN/Inf, oversized; here against the driver's own record of the bench's samples,
// SampleTimeline: it must answer a sample the bench published, at that sample's time) and a bad
// one is counted and reported, never applied. A good one is clamped to each control's range and
// slew-limited (max_slew_per_s × the driver's own time since the last applied command: a
// command's timestamps never widen the limit); the state says which stages were limited. The
// range and the slew limit are the device's own (WaveplateBackend::limits(), finite), narrowed
// by the scenario's stage ranges and --max-slew-per-s, never removed. Bookkeeping is bounded
// and wrap-safe: no number a command carries makes the driver loop or overflow.
//
// Ramps. A command may carry φ̇ (phi_rate_per_s): the waveplates then move along
// φ + φ̇·(t − t_sample) in bench time (t_sample: the answered sample's time in the driver's
// record), so a command that arrived late is where it should be now, whatever the loop's
// delay and its jitter. The motion is bounded: it stops after
// max_ramp_s (the next command normally replaces it long before), or when the first stage
// reaches its range end (a stage already at its end with φ̇ pointing out gets no rate), and
// |φ̇| ≤ the slew limit. Holding turns the motion into the point where it ends, with no rate.
//
// Bumpless switching is the controllers' part: a standby controller follows the applied φ from
// the state, so its first obeyed command continues from there.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"
#include "dpc/optics/waveplate_chain.h"
#include "sample_timeline.h"
#include "waveplate_backend.h"

namespace dpc::services {

struct DriverSettings {
  std::string driver_id = "driver";
  double max_slew_per_s = 0.0;        ///< φ units per second; 0: the device's own limit
  double min_silence_s = 1.5e-3;      ///< shortest silence that counts as a dead controller
  double silence_intervals = 8.0;     ///< or this many of its command intervals, if longer
  double holding_state_period_s = 5e-3;  ///< state heartbeat while holding
  double max_ramp_s = 2e-3;           ///< a command's rate moves φ for at most this (bench time)
};

class DriverCore {
 public:
  /// `stages` validated (ValidateDeviceStages); `backend` outlives the core and starts at
  /// `initial_phi` (inside the ranges). Throws std::invalid_argument if the backend's limits are
  /// not finite and positive.
  DriverCore(std::vector<StageConfig> stages, DriverSettings settings, WaveplateBackend* backend);

  /// A sample the polarimeter published (the driver's own record of the bench: SampleTimeline).
  /// Returns true if it shows a new bench run (numbering from 1 again): nobody is behind.
  bool OnSample(uint64_t sequence, int64_t sample_time_ns, int64_t publish_time_ns);

  /// A well-formed command (bus::ReadCommand) arrived at `now_ns` (monotonic) / `wall_ns`
  /// (wall clock). Returns the state to publish: after applying it (obeyed controller), after
  /// refusing it (so a lockstep bench still gets its answer), or when it made this controller
  /// the obeyed one; nullopt for a standby controller's command or one that answers no sample of
  /// the bench.
  std::optional<DriverState> OnCommand(const ControllerCommand& command, int64_t now_ns, int64_t wall_ns);
  /// A malformed command (`reason`: why bus::ReadCommand refused it) from `controller_id`,
  /// answering `answers_sample`: counted and reported; if it came from the obeyed controller,
  /// its sample is answered with φ unchanged (a lockstep bench waits for it).
  std::optional<DriverState> OnMalformedCommand(const std::string& controller_id, uint64_t answers_sample,
                                                const std::string& reason, int64_t wall_ns);

  /// Periodic check at `now_ns`: failover or hold when the obeyed controller fell silent, and
  /// the holding heartbeat. Returns the state to publish, if any.
  std::optional<DriverState> Tick(int64_t now_ns, int64_t wall_ns);

  /// When Tick next has something to do (monotonic ns): the obeyed controller's silence
  /// deadline, or the next holding heartbeat. The ticker sleeps until then (capped by its
  /// period), instead of waking every period while commands flow.
  int64_t NextTickNs() const;

  /// The current state, without numbering it (inspection).
  DriverState State(int64_t wall_ns) const;
  /// The current state as the next one to publish (e.g. the first, at start-up): its
  /// sequence is one more than the previous published state's, starting at 1.
  DriverState Publishable(int64_t wall_ns);

  const std::string& obeyed() const { return obeyed_; }
  /// The newest sample the bench published, as far as the driver knows (0: none yet).
  uint64_t newest_sample() const { return timeline_.newest(); }
  bool holding() const { return obeyed_.empty(); }
  int control_count() const { return chain_.control_count(); }
  /// The slew limit in force (the device's, or --max-slew-per-s if lower), φ units per second.
  double max_slew_per_s() const { return max_slew_per_s_; }
  uint64_t commands_rejected() const { return rejected_; }
  const std::string& last_rejection() const { return last_rejection_; }

 private:
  struct ControllerRecord {
    int32_t priority = 0;
    int64_t last_command_ns = 0;
    double mean_interval_ns = 0.0;    ///< exponential average; 0 until two commands
    uint64_t commands = 0;
    uint64_t last_answered = 0;       ///< the newest sample it answered
  };
  /// Liveness, judged by its silence and the other controllers' answers. Silent for longer
  /// than its timeout and: kBehind (dead), another controller answered a sample it has not
  /// answered, longer ago than a grace (a quarter of the timeout, at least 4 command
  /// intervals); kSilent, nobody answered anything newer (no samples, a stalled machine, or it
  /// was the only controller). Otherwise kAlive.
  enum class Liveness { kAlive, kBehind, kSilent };
  Liveness Judge(const ControllerRecord& record, int64_t now_ns) const;
  uint64_t Lag(const ControllerRecord& record) const { return newest_answered_ - record.last_answered; }
  /// When another controller first answered the oldest sample `record` has not answered
  /// (INT64_MIN if that is too long ago to remember). Only for Lag(record) > 0.
  int64_t BehindSinceNs(const ControllerRecord& record) const;
  int64_t BehindGraceNs(const ControllerRecord& record) const;
  int64_t SilenceTimeoutNs(const ControllerRecord& record) const;
  /// "<id> silent for X ms, N samples behind".
  std::string DescribeBehind(const std::string& id, const ControllerRecord& record, int64_t now_ns) const;
  bool Alive(const ControllerRecord& record, int64_t now_ns) const;
  /// Notes the sample a command answers (one that passed SampleTimeline::CheckAnswer).
  void NoteAnswer(ControllerRecord* record, uint64_t answers_sample, int64_t now_ns);
  /// When each of the latest kAnswerRing samples was first answered, by any controller.
  static constexpr size_t kAnswerRing = 1024;
  struct FirstAnswer {
    uint64_t sample = 0;
    int64_t time_ns = 0;
  };
  /// The best alive controller other than `excluded`, or "" if none.
  std::string BestAlive(int64_t now_ns, const std::string& excluded) const;
  void Obey(const std::string& id, const std::string& reason);
  void Hold(const std::string& reason);
  void Reject(const std::string& controller_id, const std::string& reason);
  /// The next state answers `sample` (its times from the record; the command's arrival at
  /// `wall_ns`).
  void Answer(uint64_t sample, int64_t wall_ns);
  /// Sets the backend's motion to where it ends, with no rate (holding).
  void StopMotion();

  WaveplateChain chain_;
  DriverSettings settings_;
  WaveplateBackend* backend_;
  std::vector<ControlRange> ranges_;   ///< per control: the device's range ∩ the stage's
  SampleTimeline timeline_;            ///< the bench's samples, as the polarimeter published them
  double max_slew_per_s_ = 0.0;        ///< the device's limit, or the setting if lower
  std::map<std::string, ControllerRecord> controllers_;

  std::string obeyed_;               ///< "" while holding
  /// While holding because no command came from anyone: the controller obeyed before; the
  /// driver waits for it (others' commands get a holding answer) unless it falls behind.
  std::string suspended_;
  uint64_t newest_answered_ = 0;     ///< the newest sample any controller answered
  std::array<FirstAnswer, kAnswerRing> first_answers_{};
  std::string reason_;
  WaveplateMotion applied_;         ///< what the backend does (its Applied())
  std::array<bool, kMaxControls> saturated_{};
  int64_t last_applied_ns_ = 0;       ///< the driver's clock when the last command was applied
  bool applied_any_ = false;
  uint64_t answers_sample_ = 0;
  int64_t sample_time_ns_ = 0;
  int64_t sample_publish_time_ns_ = 0;
  int64_t command_receive_time_ns_ = 0;
  int64_t last_state_ns_ = 0;
  uint64_t sequence_ = 0;
  uint64_t applied_count_ = 0;
  uint64_t rejected_ = 0;
  uint64_t limited_ = 0;
  uint64_t switches_ = 0;
  std::string last_rejection_;
};

}  // namespace dpc::services
