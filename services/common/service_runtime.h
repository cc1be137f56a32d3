#pragma once
// What every bench service shares besides its skeleton (service.h): the common command-line
// options (--domain, --bench-id, the scenario file and the `dpc sim` override flags), the
// scenario (a file or the embedded default), logging, and rate-limited reports of rejected
// input.

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include <CLI/CLI.hpp>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/cli/exit_code.h"
#include "dpc/cli/scenario_overrides.h"

namespace dpc::services {

struct CommonOptions {
  int domain_id = 0;
  std::string bench_id = "bench1";
  std::string scenario_file;   ///< empty: the embedded default (deploy/scenarios/bench_default.pbtxt)
  std::string log_level = "info";
  cli::ScenarioOverrides overrides;   ///< the `dpc sim` flags (--method, --step, --rate-rad-per-s, …)
  std::string security_dir;    ///< DDS Security credentials (make-bench-pki.sh); empty: off
  std::string identity;        ///< the identity in it; empty: the service's own role
  int realtime_priority = 0;   ///< SCHED_FIFO priority (1–99) for the service's threads; 0: off
  double stuck_exit_s = 10.0;  ///< the loop guard's turn limit (LoopGuard); 0: off
};

/// "" if `id` may name a bench or a controller (1–63 of A–Z a–z 0–9 _ -: it becomes part of a
/// DDS partition and a certificate's name, so no wildcards or dots); else why not.
std::string IdentifierProblem(const std::string& id);

/// Adds --domain, --bench-id, the positional SCENARIO, --log-level, --security-dir and
/// --identity (also from $DPC_SECURITY_DIR, $DPC_IDENTITY), --realtime-priority, --stuck-exit-s
/// and the scenario override flags of `dpc sim`.
void AddCommonOptions(CLI::App& app, CommonOptions* options);

/// The text of deploy/scenarios/bench_default.pbtxt, compiled in.
const char* DefaultBenchScenarioText();

/// The scenario file's contents, or the embedded default, with the override flags applied;
/// unvalidated (each service validates the parts it uses). Throws ScenarioError.
ScenarioConfig LoadServiceScenario(const CommonOptions& options);
/// The same with another embedded default: `default_text` (a scenario's text format, named
/// `default_name` in syntax errors) when no file is given. dpc-emulator's true device.
ScenarioConfig LoadServiceScenario(const CommonOptions& options, const char* default_text,
                                   const std::string& default_name);

/// "invalid scenario: controller.step: … (set by --step)".
std::string DescribeError(const ScenarioError& error, const CommonOptions& options);

/// Puts the calling thread, and the threads it starts from then on (Fast DDS's), under
/// SCHED_FIFO at `priority` (0: leaves the scheduling as it is). On a busy machine this keeps
/// the bench's processes running while others (a kill -9 being reaped, a build) wait. Returns
/// why it could not (it needs CAP_SYS_NICE or an RLIMIT_RTPRIO as high), or "".
std::string ApplyRealtimePriority(int priority);

/// Sets up spdlog ("[driver bench1] …" on stderr) at options.log_level (one of the names
/// --log-level accepts; the option checks it). Calling it again replaces the logger.
void SetUpLogging(const std::string& service, const CommonOptions& options);

/// Logs what happens to remote participants (discovered, gone, authenticated, refused by DDS
/// Security) from Fast DDS's threads: at most kLines lines per kWindow, so that a peer creating
/// participants in a loop cannot flood the log; the next line logged says how many were not.
class PeerLog {
 public:
  static constexpr int kLines = 20;
  static constexpr int64_t kWindowNs = 10'000'000'000;
  using Now = std::function<int64_t()>;  ///< monotonic nanoseconds
  /// `now` defaults to the monotonic clock.
  explicit PeerLog(Now now = nullptr);
  /// `warning`: a refusal (logged as a warning), else info.
  void operator()(bool warning, const std::string& text);

 private:
  Now now_;
  std::mutex mutex_;
  int64_t window_start_ns_ = 0;
  bool started_ = false;
  int lines_in_window_ = 0;
  uint64_t not_shown_ = 0;
};

/// One line in the service's log: an error, or information (e.g. bus::ParticipantMaker's).
void LogLine(bool error, const std::string& text);

/// A PeerLog of its own behind a copyable function (for BusOptions::on_peer, through
/// bus::DescribedPeerEvents).
std::function<void(bool warning, const std::string& text)> PeerLogger();

/// Logs rejected input without letting a flood of it stall the loop: the first rejection, then
/// one line per kEvery more, each with the running count and the latest reason.
class RejectionLog {
 public:
  static constexpr uint64_t kEvery = 1000;
  explicit RejectionLog(std::string what) : what_(std::move(what)) {}
  /// Call after anything that may have rejected input, with the total so far.
  void Update(uint64_t count, const std::string& last_reason);

 private:
  std::string what_;
  uint64_t reported_ = 0;
};

}  // namespace dpc::services
