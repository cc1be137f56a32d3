#pragma once
// `dpc monitor`: the bench's live status on one line.
//
//   dpc monitor [--domain N] [--bench-id ID] [--rate-hz 5] [--lines] [--duration-s T]
//
// Subscribes to dpc_stokes_sample, dpc_waveplate_state, dpc_controller_status and dpc_target
// of one bench and, --rate-hz times a second, shows:
//   error_deg   mean (and max) angle from the measured S_out to the current target over the
//               last update period (dpc::Target::DistanceRad of the bus's target)
//   phi         the φ the driver applies now
//   rate_hz     samples per second received (measured)
//   the driver's mode: ACTIVE and the obeyed controller (priority), or HOLDING and its reason
//   missed_deadlines per controller (their DDS deadline misses on the sample topic)
//   the target's revision
// Every line starts with the loop's condition and how long it has held: LOCKED (the period's
// mean error below --lock-threshold-deg), LOST, HOLDING (the driver holds), NO SAMPLES, or
// WAITING (nothing seen yet).
// On a terminal the line is redrawn in place ('\r') and fitted to the terminal's width: the
// fields that matter least go first (missed deadlines, the target's revision, φ, the rate),
// the holding reason is cut to what is left, and nothing ever wraps. Otherwise (or with
// --lines) one full line per update is printed. Runs until SIGINT/SIGTERM or --duration-s,
// then exits 0.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/cli/exit_code.h"
#include "bus_tool_support.h"
#include "dpc/control/target.h"
#include "dpc/msg/bench.h"

namespace dpc::tools {

struct MonitorOptions {
  BusToolOptions bus;
  double rate_hz = 5.0;
  double lock_threshold_deg = 10.0;
  int width = 0;  ///< 0: the terminal's (redrawing) or unlimited (--lines)
  bool lines = false;
  double duration_s = 0.0;  ///< 0: until stopped
};

CLI::App* AddMonitorCommand(CLI::App& app, MonitorOptions* options);

cli::ExitCode RunMonitorCommand(const MonitorOptions& options);

/// The number of characters (Unicode code points) of UTF-8 `text`.
size_t DisplayWidth(const std::string& text);

/// What the monitor has seen, folded from the bus's messages (not thread-safe: the command
/// guards it with a mutex). Separate from the DDS wiring so that the line can be tested.
class MonitorState {
 public:
  explicit MonitorState(double lock_threshold_deg = 10.0) : lock_threshold_deg_(lock_threshold_deg) {}
  void OnSample(const msg::StokesSample& sample);
  void OnState(const msg::WaveplateState& state);
  void OnStatus(const msg::ControllerStatus& status);
  void OnTarget(const msg::Target& target);

  /// The status line for the period of `elapsed_s` since the last call; starts a new period.
  /// `width` > 0: the compact line, at most that many characters (code points) wide.
  std::string TakeLine(double elapsed_s, int width = 0);

 private:
  enum class Condition { kWaiting, kLocked, kLost, kHolding, kNoSamples };
  static const char* Name(Condition condition);
  double lock_threshold_deg_;
  double clock_s_ = 0.0;  ///< the sum of the periods so far
  Condition condition_ = Condition::kWaiting;
  double condition_since_s_ = 0.0;
  struct Controller {
    uint64_t missed_deadlines = 0;
    std::string condition;
  };
  std::optional<Target> target_;
  uint64_t target_revision_ = 0;
  std::string target_problem_;
  // The current period.
  int64_t period_samples_ = 0;
  int64_t period_errors_ = 0;
  double period_error_sum_deg_ = 0.0;
  double period_error_max_deg_ = 0.0;
  int64_t total_samples_ = 0;
  // The latest state.
  bool have_state_ = false;
  std::vector<double> phi_applied_;
  bool active_ = false;
  std::string reason_;
  std::string obeyed_id_;
  int32_t obeyed_priority_ = 0;
  std::map<std::string, Controller> controllers_;
};

}  // namespace dpc::tools
