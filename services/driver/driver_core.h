#pragma once
// The waveplate driver's logic, without DDS: which controller to obey, what to apply, what to
// report. The DDS wiring (main.cc) calls it under one lock, with monotonic time in ns.
//
// Which controller it obeys is the ControllerArbiter's decision (controller_arbiter.h): the
// alive controller of highest priority, judged by its silence and the other controllers'
// answers. Tick() runs when the arbiter's next deadline (or the holding heartbeat) is due; when
// it fails over, the new controller's latest command (kept for every standby) is applied at
// once, so the gap does not grow by a sample period.
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
// Stand-ins. When a standby answered a sample and the obeyed controller has not answered it
// ControllerArbiter::StandInWaitNs() later (its usual lateness and a margin), the standby's
// answer is applied in its place (by the ticker when the wait is over, or as the standby's next
// answer arrives if the ticker woke late), checked, clamped and slew-limited as any other; the state
// names whose command it applied (applied_controller_id) and counts the stand-ins. So the
// waveplates never wait for the arbiter's grace: a killed controller's commands are replaced
// one wait after the standby's next answer, and a primary that is late once loses that sample
// only, not control. An answer to a sample older than one already answered is not applied (the
// waveplates never go back in bench time).
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
#include "controller_arbiter.h"
#include "sample_timeline.h"
#include "waveplate_backend.h"

namespace dpc::services {

struct DriverSettings {
  std::string driver_id = "driver";
  double max_slew_per_s = 0.0;        ///< φ units per second; 0: the device's own limit
  double min_silence_s = 10e-3;       ///< the grace of a controller behind the others (ControllerArbiter)
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

  /// How many command writers the driver's reader is matched with (the DDS layer's count; -1:
  /// not known). While none is and the driver holds, its state says so: a silence that
  /// started with the last controller leaving is no hiccup to wait out.
  void SetControllersConnected(int count) { controllers_connected_ = count; }

  const std::string& obeyed() const { return arbiter_.obeyed(); }
  /// The newest sample the bench published, as far as the driver knows (0: none yet).
  uint64_t newest_sample() const { return timeline_.newest(); }
  bool holding() const { return arbiter_.holding(); }
  int control_count() const { return chain_.control_count(); }
  /// The slew limit in force (the device's, or --max-slew-per-s if lower), φ units per second.
  double max_slew_per_s() const { return max_slew_per_s_; }
  uint64_t commands_rejected() const { return rejected_; }
  const std::string& last_rejection() const { return last_rejection_; }

 private:
  /// A controller's command and when it arrived (wall clock).
  struct Received {
    ControllerCommand command;
    int64_t wall_ns = 0;  ///< when it arrived
  };
  void Reject(const std::string& controller_id, const std::string& reason);
  /// The next state answers `sample` (its times from the record; the command's arrival at
  /// `wall_ns`).
  void Answer(uint64_t sample, int64_t wall_ns);
  /// Sets the backend's motion to where it ends, with no rate (holding).
  void StopMotion();
  /// Clamps, slew-limits and applies a command (the obeyed controller's, or a standby's
  /// standing in or taking over) at `now_ns`; `received_wall_ns`: when it arrived (the state's
  /// command_receive_time_ns). The state to publish.
  DriverState Apply(const ControllerCommand& command, int64_t now_ns, int64_t received_wall_ns);
  /// Remembers a standby's latest command (arrived at `wall_ns`): applied at once if the standby
  /// takes over.
  void KeepStandbyCommand(const ControllerCommand& command, int64_t wall_ns);
  /// A standby's command (arrived at `now_ns`) for a sample the obeyed controller has not
  /// answered: kept to stand in for it when the wait is over, or applied now if the wait for an
  /// older sample the obeyed controller still owes is already over (the ticker may not have run:
  /// a busy machine wakes it late). The state to publish, if it was applied.
  std::optional<DriverState> ConsiderStandIn(const ControllerCommand& command, int64_t now_ns, int64_t wall_ns);
  /// While a controller is obeyed: `sample` is newer than every answered one and the obeyed
  /// controller has not answered it (another controller's answer may stand in).
  bool ObeyedOwes(uint64_t sample) const;
  /// Applies a standby's answer in the obeyed controller's place, counted.
  DriverState ApplyStandIn(const Received& answer, int64_t now_ns);

  WaveplateChain chain_;
  DriverSettings settings_;
  WaveplateBackend* backend_;
  std::vector<ControlRange> ranges_;   ///< per control: the device's range ∩ the stage's
  SampleTimeline timeline_;            ///< the bench's samples, as the polarimeter published them
  double max_slew_per_s_ = 0.0;        ///< the device's limit, or the setting if lower
  ControllerArbiter arbiter_;
  std::map<std::string, Received> standby_commands_;  ///< each standby's latest
  struct StandIn {
    Received answer;
    int64_t due_ns = 0;  ///< applied then if the obeyed controller has not answered its sample
  };
  std::optional<StandIn> stand_in_;
  uint64_t stand_ins_ = 0;
  std::string applied_by_;            ///< whose command the applied φ came from
  uint64_t newest_answered_ = 0;      ///< the newest sample a state answered (this bench run)
  WaveplateMotion applied_;         ///< what the backend does (its Applied())
  std::array<bool, kMaxControls> saturated_{};
  int64_t last_applied_ns_ = 0;       ///< the driver's clock when the last command was applied
  bool applied_any_ = false;
  int controllers_connected_ = -1;
  uint64_t answers_sample_ = 0;
  int64_t sample_time_ns_ = 0;
  int64_t sample_publish_time_ns_ = 0;
  int64_t command_receive_time_ns_ = 0;
  int64_t last_state_ns_ = 0;
  uint64_t sequence_ = 0;
  uint64_t applied_count_ = 0;
  uint64_t rejected_ = 0;
  uint64_t limited_ = 0;
  std::string last_rejection_;
};

}  // namespace dpc::services
