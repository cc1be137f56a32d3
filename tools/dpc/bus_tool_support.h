#pragma once
// What the DDS commands of `dpc` (topic, target, monitor) share: --domain and --bench-id, clean
// stop on SIGINT/SIGTERM (so that the DDS entities are deleted and no /dev/shm segment stays
// behind), and waiting on a condition with a deadline.

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <functional>
#include <string>

#include "dpc/bus/bus_participant.h"

namespace dpc::tools {

struct BusToolOptions {
  int domain_id = 0;
  std::string bench_id = "bench1";
  std::string security_dir;  ///< DDS Security credentials; empty: off
  std::string identity;      ///< empty: the command's role (observer; operator for `dpc target`)

  /// The participant's options: this domain, `name`, the credentials of `identity` (or of
  /// `default_identity`).
  bus::BusOptions Participant(const std::string& name, const std::string& default_identity) const;
};

/// Adds --domain (0…232), --security-dir and --identity (also $DPC_SECURITY_DIR, $DPC_IDENTITY)
/// and, if `bench_help` is not null, --bench-id with that help text.
void AddBusToolOptions(CLI::App& command, BusToolOptions* options, const char* bench_help);

/// The bench filter for bus::BusParticipant::MakeReader: "" (all benches) for "" or "*".
std::string BenchFilter(const std::string& bench_id);

/// While alive, SIGINT, SIGTERM and SIGHUP (a closed terminal, or a reload signal sent to the
/// whole bench) set a flag instead of killing the process, so that a recording is closed
/// properly; SIGPIPE is ignored, so that `dpc topic echo … | head` ends cleanly too. Restores
/// the old handlers.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// True once SIGINT, SIGTERM or SIGHUP arrived.
  static bool requested();

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
  struct sigaction old_hup_ {};
  struct sigaction old_pipe_ {};
};

/// Polls `done` every few milliseconds until it is true (returns true), the deadline passes or a
/// stop signal arrives (returns false). A zero or negative `timeout_s` means no deadline.
bool WaitFor(const std::function<bool()>& done, double timeout_s);

/// Seconds since `start` on the steady clock.
double SecondsSince(std::chrono::steady_clock::time_point start);

}  // namespace dpc::tools
