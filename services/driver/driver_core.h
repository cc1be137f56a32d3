#pragma once
// The waveplate driver's logic, without DDS: which controller to obey, what to apply, what to
// report. The DDS wiring (main.cc) calls it under one lock, with monotonic time in ns.
//
// Arbitration. Every controller publishes a command for every sample; the driver obeys exactly
// one: the highest-priority controller that is alive (ties: the one already obeyed). A
// controller is alive while its last command is younger than its silence timeout:
//   timeout = max(min_silence_s, silence_intervals × its mean command interval)
// (the interval is an exponential average of its command arrivals), so at 10 kHz a killed
// controller is noticed ~2 ms after its last command, where the DDS deadline (≥ 10 ms on Fast
// DDS 2.9) would take five times longer. Tick() runs when that deadline is due (at most every
// 0.25 ms) and switches to the next alive controller, or holds the last good φ and says why.
//
// Every command is checked (CheckCommandShape: stage count, NaN/Inf, oversized) and a bad one
// is counted and reported, never applied. A good one is clamped to each stage's range and
// slew-limited (max_slew_per_s × the bench time since the last applied command); the state
// says which stages were limited.
//
// Ramps. A command may carry φ̇ (phi_rate_per_s): the waveplates then move along
// φ + φ̇·(t − sample_time) in bench time, so a command that arrived late is where it should be
// now, whatever the loop's delay and its jitter. The motion is bounded: it stops after
// max_ramp_s (the next command normally replaces it long before), or when the first stage
// reaches its range end (a stage already at its end with φ̇ pointing out gets no rate), and
// |φ̇| ≤ max_slew_per_s. Holding turns the motion into the point where it ends, with no rate.
//
// Bumpless switching is the controllers' part: a standby controller follows the applied φ from
// the state, so its first obeyed command continues from there.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/msg/bench.h"
#include "dpc/optics/waveplate_chain.h"
#include "waveplate_backend.h"

namespace dpc::services {

struct DriverSettings {
  std::string bench_id = "bench1";
  std::string driver_id = "driver";
  double max_slew_per_s = 0.0;        ///< φ units per second of bench time; 0: no limit
  double min_silence_s = 2e-3;        ///< shortest silence that counts as a dead controller
  double silence_intervals = 8.0;     ///< or this many of its command intervals, if longer
  double holding_state_period_s = 5e-3;  ///< state heartbeat while holding
  double max_ramp_s = 2e-3;           ///< a command's rate moves φ for at most this (bench time)
};

class DriverCore {
 public:
  /// `stages` validated (ValidateDeviceStages); `backend` outlives the core and starts at
  /// `initial_phi` (inside the ranges).
  DriverCore(std::vector<StageConfig> stages, DriverSettings settings, WaveplateBackend* backend);

  /// A command arrived at `now_ns` (monotonic) / `wall_ns` (wall clock). Returns the state to
  /// publish: after applying it (obeyed controller), after refusing it (so a lockstep bench
  /// still gets its answer), or when it made this controller the obeyed one; nullopt for a
  /// standby controller's command.
  std::optional<msg::WaveplateState> OnCommand(const msg::WaveplateCommand& command,
                                               int64_t now_ns, int64_t wall_ns);

  /// Periodic check at `now_ns`: failover or hold when the obeyed controller fell silent, and
  /// the holding heartbeat. Returns the state to publish, if any.
  std::optional<msg::WaveplateState> Tick(int64_t now_ns, int64_t wall_ns);

  /// When Tick next has something to do (monotonic ns): the obeyed controller's silence
  /// deadline, or the next holding heartbeat. The ticker sleeps until then (capped by its
  /// period), instead of waking every period while commands flow.
  int64_t NextTickNs() const;

  /// The current state, without numbering it (inspection).
  msg::WaveplateState State(int64_t wall_ns) const;
  /// The current state as the next one to publish (e.g. the first, at start-up): its
  /// sequence_number is one more than the previous published state's, starting at 1.
  msg::WaveplateState Publishable(int64_t wall_ns);

  const std::string& obeyed() const { return obeyed_; }
  bool holding() const { return obeyed_.empty(); }
  int control_count() const { return chain_.control_count(); }
  uint64_t commands_rejected() const { return rejected_; }
  const std::string& last_rejection() const { return last_rejection_; }

 private:
  struct ControllerRecord {
    int32_t priority = 0;
    int64_t last_command_ns = 0;
    double mean_interval_ns = 0.0;    ///< exponential average; 0 until two commands
    uint64_t commands = 0;
  };
  int64_t SilenceTimeoutNs(const ControllerRecord& record) const;
  bool Alive(const ControllerRecord& record, int64_t now_ns) const;
  /// The best alive controller other than `excluded`, or "" if none.
  std::string BestAlive(int64_t now_ns, const std::string& excluded) const;
  void Obey(const std::string& id, const std::string& reason);
  void Hold(const std::string& reason);
  void Reject(const std::string& controller_id, const std::string& reason);
  /// Sets the backend's motion to where it ends, with no rate (holding).
  void StopMotion();

  WaveplateChain chain_;
  DriverSettings settings_;
  WaveplateBackend* backend_;
  std::map<std::string, ControllerRecord> controllers_;

  std::string obeyed_;               ///< "" while holding
  std::string reason_;
  bus::AppliedTrajectory applied_;  ///< what the backend does (its Applied())
  std::vector<bool> saturated_;
  int64_t last_applied_sample_time_ns_ = 0;
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
