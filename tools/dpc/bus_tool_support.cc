#include "bus_tool_support.h"

#include <fmt/core.h>

#include <thread>

#include "dpc/bench/clock.h"
#include "dpc/bus/event_thread_canary.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

std::atomic<bool> g_stop_requested{false};

extern "C" void OnStopSignal(int) { g_stop_requested.store(true); }

}  // namespace

void AddBusToolOptions(CLI::App& command, BusToolOptions* options, const char* bench_help) {
  command.add_option("--domain", options->domain_id, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  if (bench_help != nullptr) {
    command.add_option("--bench-id", options->bench_id, bench_help)->capture_default_str();
  }
  command.add_option("--security-dir", options->security_dir,
                     "DDS Security: the bench's credentials (deploy/security/make-bench-pki.sh). Empty: off")
      ->envname("DPC_SECURITY_DIR")
      ->check(CLI::ExistingDirectory);
  command.add_option("--identity", options->identity,
                     "DDS Security: the identity in --security-dir (default: observer; operator for dpc target)")
      ->envname("DPC_IDENTITY");
}

bus::BusOptions BusToolOptions::Participant(const std::string& name, const std::string& default_identity) const {
  return bus::BusOptions{domain_id, name, {security_dir, identity.empty() ? default_identity : identity},
                         udp_receive_buffer_bytes};
}

ObserverParticipant::ObserverParticipant(const BusToolOptions& options, const std::string& command,
                                         const std::string& default_identity)
    : maker_(options.Participant(command, default_identity), {},
             [command](bool, const std::string& text) { fmt::print(stderr, "{}: {}\n", command, text); },
             bus::HandshakeWatchdog::Starving::kObserver),
      participant_(maker_.Make()),
      settled_ns_(MonotonicNs()) {}

bool ObserverParticipant::Heal(const std::function<void()>& delete_endpoints,
                               const std::function<void()>& make_endpoints) {
  if (!participant_->secure()) return false;
  const int64_t now_ns = MonotonicNs();
  if (!maker_.preparing()) {
    if (now_ns < next_look_ns_) return false;
    next_look_ns_ = now_ns + bus::HandshakeWatchdog::kCheckPeriodNs;
    if (participant_->PendingHandshakes(0).empty()) settled_ns_ = now_ns;
  }
  const auto cause = maker_.ReloadCause(false, *participant_, now_ns, settled_ns_);
  if (!cause || !maker_.Reload(&participant_, delete_endpoints, make_endpoints, *cause)) return false;
  ++reloads_;
  return true;
}

std::string BenchFilter(const std::string& bench_id) {
  return bench_id == "*" ? std::string() : bench_id;
}

StopSignals::StopSignals() {
  g_stop_requested.store(false);
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &old_int_);
  sigaction(SIGTERM, &action, &old_term_);
  sigaction(SIGHUP, &action, &old_hup_);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, &old_pipe_);
}

StopSignals::~StopSignals() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
  sigaction(SIGHUP, &old_hup_, nullptr);
  sigaction(SIGPIPE, &old_pipe_, nullptr);
}

bool StopSignals::requested() { return g_stop_requested.load(); }

void AddStuckExitOption(CLI::App& command, double* seconds, const std::string& what) {
  command.add_option("--stuck-exit-s", *seconds,
                     "Exit with code 1, saying where, when the command's loop has not turned for this long (a "
                     "call into Fast DDS or a write that never returns)" + what +
                         ", or when the event thread of its DDS participant has not run for 3 s (a Fast DDS "
                         "deadlock). 0: never")
      ->envname("DPC_STUCK_EXIT_S")
      ->check(cli::StuckExitProblem)
      ->capture_default_str();
}

std::unique_ptr<cli::LoopGuard> GuardCommandLoop(const std::string& command, double stuck_exit_s,
                                                 const std::string& after) {
  return std::make_unique<cli::LoopGuard>(
      stuck_exit_s, cli::LoopGuard::kStopGraceS,
      [command, after](const std::string& why) {
        cli::ExitAfterSaying([command, after, why] { fmt::print(stderr, "\ndpc {}: {}{}\n", command, why, after); },
                             cli::ToInt(cli::ExitCode::kRuntimeError));
      },
      [] { return StopSignals::requested(); },
      stuck_exit_s > 0 ? cli::Heartbeat{bus::OldestEventThreadTickNs, bus::kEventThreadStuckS, bus::kEventThreadWhat}
                       : cli::Heartbeat{});
}

bool WaitFor(const std::function<bool()>& done, double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    if (done()) return true;
    if (StopSignals::requested()) return false;
    if (timeout_s > 0 && SecondsSince(start) >= timeout_s) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace dpc::tools
