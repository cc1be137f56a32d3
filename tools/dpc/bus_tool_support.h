#pragma once
// What the DDS commands of `dpc` (topic, target, monitor) share: --domain and --bench-id, clean
// stop on SIGINT/SIGTERM (so that the DDS entities are deleted and no /dev/shm segment stays
// behind), and waiting on a condition with a deadline.

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "dpc/bus/bus_participant.h"
#include "dpc/bus/participant_maker.h"
#include "dpc/cli/loop_guard.h"

namespace dpc::tools {

struct BusToolOptions {
  int domain_id = 0;
  std::string bench_id = "bench1";
  std::string security_dir;  ///< DDS Security credentials; empty: off
  std::string identity;      ///< empty: the command's role (observer; operator for `dpc target`)
  uint32_t udp_receive_buffer_bytes = 0;  ///< bus::BusOptions's; 0: the profile's

  /// The participant's options: this domain, `name`, the credentials of `identity` (or of
  /// `default_identity`).
  bus::BusOptions Participant(const std::string& name, const std::string& default_identity) const;
};

/// A long-running command's participant (record, monitor, dashboard, topic echo/hz). With DDS
/// Security it heals a stalled handshake by itself, as the services do: when a peer's handshake
/// has had no outcome for 4 s (so nothing of that peer's reaches the command), a line on stderr
/// names the peer, and the participant and the command's endpoints are made again
/// (bus::ParticipantMaker, bus::HandshakeWatchdog as an observer). While some handshake stays
/// pending (a peer that never answers), the next such reload comes after 30 s, then twice as late
/// each time, up to 10 min; once none is pending, the back-off starts over.
class ObserverParticipant {
 public:
  /// `command`: the participant's name and the prefix of the lines on stderr ("dpc record").
  /// Throws as bus::BusParticipant does.
  ObserverParticipant(const BusToolOptions& options, const std::string& command, const std::string& default_identity);

  bus::BusParticipant& operator*() const { return *participant_; }
  bus::BusParticipant* operator->() const { return participant_.get(); }

  /// From the command's loop, on the thread that owns the endpoints, as often as convenient (it
  /// looks at most once a second). If a handshake stalled: a new participant; once it has
  /// authenticated the old one's peers (at most 3 s later; the old one serves meanwhile),
  /// `delete_endpoints` (the old participant's; readers first), the participant replaced, and
  /// `make_endpoints` on the new one; true then. False (nothing changed) otherwise, and
  /// without DDS Security.
  bool Heal(const std::function<void()>& delete_endpoints, const std::function<void()>& make_endpoints);

  /// What Heal tells the command's loop guard while it runs (bus::ParticipantMaker::PhaseReport).
  void SetPhaseReport(bus::ParticipantMaker::PhaseReport report) { maker_.SetPhaseReport(std::move(report)); }

  /// How many times Heal made the participant again.
  uint64_t reloads() const { return reloads_; }

 private:
  bus::ParticipantMaker maker_;
  std::unique_ptr<bus::BusParticipant> participant_;
  int64_t settled_ns_;  ///< when it last had no handshake pending (MonotonicNs)
  int64_t next_look_ns_ = 0;
  uint64_t reloads_ = 0;
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

/// --stuck-exit-s of a long-running command: the turn limit of its loop guard (`what` ends the
/// help: what the program leaves behind when it exits so).
void AddStuckExitOption(CLI::App& command, double* seconds, const std::string& what);

/// The guard of a long-running command's loop (cli::LoopGuard; the caller turns it): a stop is a
/// stop signal (StopSignals::requested) or Stopping(); stuck, it prints "dpc <command>: <why><after>"
/// on stderr and the process exits with code 1. `stuck_exit_s` 0: only the stop is guarded.
std::unique_ptr<cli::LoopGuard> GuardCommandLoop(const std::string& command, double stuck_exit_s,
                                                 const std::string& after = {});

/// Polls `done` every few milliseconds until it is true (returns true), the deadline passes or a
/// stop signal arrives (returns false). A zero or negative `timeout_s` means no deadline.
bool WaitFor(const std::function<bool()>& done, double timeout_s);

/// Seconds since `start` on the steady clock.
double SecondsSince(std::chrono::steady_clock::time_point start);

}  // namespace dpc::tools
