#pragma once
// The skeleton every bench service shares, after the Fast DDS examples and Fast DDS Spy: a
// service is a class whose constructor builds everything (scenario, participant, writers,
// readers) and throws on any failure, whose run() does the work until stop() or until the work
// ends, and whose stop() wakes run() at once (a condition variable, not a polling loop).
// ServiceMain is the whole main() of a service: options, logging, construction, signals, run,
// and the exit code (cli::ExitCode):
//
//   bad command line                     kInvalidInput (2), the parser's message
//   invalid scenario or configuration    kInvalidInput (2), the field (and the flag that set it)
//   cannot start (DDS, device, profiles) kInitializationError (4)
//   failed while running                 kRuntimeError (1)
//   SIGINT / SIGTERM                     stop() at once; run() ends cleanly: kOk (0)
//   SIGHUP                               RequestReload(): the service makes its DDS participant
//                                        again from the credentials and profiles on disk (a
//                                        rotation of DDS Security credentials without a restart)
//   stuck: its loop has not turned for   kRuntimeError (1) at once, saying where it
//   --stuck-exit-s, or it has not ended  was stuck (cli::LoopGuard): a supervisor
//   8 s after a stop                     restarts it
//
// SIGINT, SIGTERM and SIGHUP are blocked in every thread (before Fast DDS starts its own) and
// taken by one watcher thread (sigwait), which calls stop() or RequestReload(): docker stops
// containers with SIGTERM.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <pthread.h>
#include <stdexcept>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "dpc/cli/command_line.h"
#include "dpc/cli/exit_code.h"
#include "dpc/cli/loop_guard.h"
#include "dpc/config/scenario_error.h"
#include "service_runtime.h"

namespace dpc::services {

/// A configuration a service refuses that is not a scenario field (an option that contradicts
/// the scenario, say): exit code kInvalidInput.
class ConfigurationError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class Service {
 public:
  virtual ~Service() = default;
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  /// Works until stop() or the end of the work; returns the exit code.
  virtual cli::ExitCode run() = 0;

  /// The longest one turn of run()'s loop may take by the service's own bounded waits (a status
  /// period, an instrument's connection timeout), in seconds; the loop guard's limit is never
  /// below it plus a margin. nullopt (the default): run() has no loop that calls Turned(), and
  /// only the stop grace is guarded.
  virtual std::optional<double> LongestTurnS() const { return std::nullopt; }
  /// What the loop guard watches besides the loop (none by default); a DDS service: the event
  /// threads of its participants (bus::EventThreadCanary). Off with --stuck-exit-s 0.
  virtual cli::Heartbeat GuardHeartbeat() const { return {}; }
  /// Before run(): the guard that Turned(), GuardPhase() and stop() report to (ServiceMain's).
  void AttachGuard(cli::LoopGuard* guard) { guard_ = guard; }

  /// Thread-safe; wakes run() (and whatever OnStop wakes) at once. Idempotent.
  void stop();
  bool stopped() const { return stopped_.load(std::memory_order_relaxed); }

  /// Thread-safe (SIGHUP): asks run() to make the service's DDS participant and its endpoints
  /// again, from the credentials and profiles as they are on disk now. A service whose new
  /// participant cannot be made keeps the one it has (and says why).
  void RequestReload() {
    reload_requested_.store(true);
    OnReloadRequested();
  }

 protected:
  Service() = default;
  /// Waits until stop() or `deadline` (steady clock); true if stopped.
  bool WaitForStopUntil(std::chrono::steady_clock::time_point deadline);
  bool WaitForStopFor(std::chrono::nanoseconds timeout) {
    return WaitForStopUntil(std::chrono::steady_clock::now() + timeout);
  }
  /// Called once by stop(), after the flag is set: wake waits of the service's own.
  virtual void OnStop() {}
  /// Called by RequestReload, after the request is recorded (from the signal watcher's thread).
  virtual void OnReloadRequested() {}
  /// Whether a reload was requested since the last call (run() polls it where it may rebuild
  /// its participant).
  bool TakeReloadRequest() { return reload_requested_.exchange(false); }
  /// One turn of run()'s loop, for the loop guard (cheap: a relaxed increment).
  void Turned() noexcept {
    if (guard_ != nullptr) guard_->Turn();
  }
  /// What run()'s loop is doing now, named in the guard's message: a string literal. Returns the
  /// phase it replaces (nullptr without a guard).
  const char* GuardPhase(const char* literal) noexcept { return guard_ != nullptr ? guard_->Phase(literal) : nullptr; }

 private:
  cli::LoopGuard* guard_ = nullptr;
  std::atomic<bool> stopped_{false};
  std::atomic<bool> reload_requested_{false};
  std::mutex mutex_;
  std::condition_variable stop_requested_;
};

/// Blocks SIGINT, SIGTERM, SIGHUP and SIGPIPE in the calling thread and every thread it starts
/// after; a watcher thread takes SIGINT and SIGTERM and calls the service's stop(), and SIGHUP,
/// its RequestReload() (ignored before the service exists). Construct on the main thread before
/// any other thread starts (Fast DDS's included).
class SignalWatcher {
 public:
  SignalWatcher();
  ~SignalWatcher();
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

  /// From now on a signal stops `service`; one that came before stops it at once.
  void Watch(Service* service);
  /// From now on signals reach no service (before it is destroyed: a signal being handled is
  /// finished first).
  void Unwatch();
  /// The signal that stopped the service (0: none).
  int signal() const { return signal_.load(); }

 private:
  void Loop();

  std::mutex mutex_;  ///< service_ and the calls into it
  Service* service_ = nullptr;
  std::atomic<int> signal_{0};
  std::atomic<bool> quitting_{false};
  std::thread thread_;
};

/// The loop guard's action: `why` logged (critical) and the process ended at once with code 1
/// (cli::ExitAfterSaying).
[[noreturn]] void ExitStuck(const std::string& why);

/// The loop guard's turn limit: `option_s` (--stuck-exit-s; 0: off), raised to `longest_turn_s`
/// plus a margin; 0 when the service has no guarded loop.
double GuardedTurnLimitS(double option_s, std::optional<double> longest_turn_s);

/// The main() of service S. S provides:
///   struct Options;                                   its own options, with defaults
///   static void AddOptions(CLI::App&, Options*);
///   static std::string LogName(const Options&);        "driver", "controller main", …
///   S(const CommonOptions&, const Options&);           builds everything; throws
///   cli::ExitCode run();                               (Service)
template <typename S>
int ServiceMain(int argc, char** argv, const std::string& description) {
  SignalWatcher signals;
  CLI::App app{description};
  CommonOptions common;
  AddCommonOptions(app, &common);
  typename S::Options options;
  S::AddOptions(app, &options);
  app.name(argc > 0 ? std::filesystem::path(argv[0]).filename().string() : "dpc-service");
  cli::AddVersionFlag(app, app.get_name());
  if (const std::string problem = cli::UnknownNameProblem(app, cli::Arguments(argc, argv)); !problem.empty()) {
    std::fprintf(stderr, "%s\nRun with --help for more information.\n", problem.c_str());
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli::ToInt(app.exit(e) == 0 ? cli::ExitCode::kOk : cli::ExitCode::kInvalidInput);
  }
  SetUpLogging(S::LogName(options), common);
  // Before the participant: its threads inherit the scheduling.
  if (const std::string problem = ApplyRealtimePriority(common.realtime_priority); !problem.empty()) {
    spdlog::error("cannot start: {}", problem);
    return cli::ToInt(cli::ExitCode::kInitializationError);
  }
  if (common.realtime_priority > 0) spdlog::info("real-time priority {} (SCHED_FIFO)", common.realtime_priority);
  std::unique_ptr<cli::LoopGuard> guard;  // outlives the service: it guards the service's deletion too
  std::unique_ptr<S> service;
  try {
    service = std::make_unique<S>(common, options);
  } catch (const ScenarioError& e) {
    spdlog::error("{}", DescribeError(e, common));
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  } catch (const ConfigurationError& e) {
    spdlog::error("invalid configuration: {}", e.what());
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  } catch (const std::exception& e) {
    spdlog::error("cannot start: {}", e.what());
    return cli::ToInt(cli::ExitCode::kInitializationError);
  }
  guard = std::make_unique<cli::LoopGuard>(
      GuardedTurnLimitS(common.stuck_exit_s, service->LongestTurnS()), cli::LoopGuard::kStopGraceS, ExitStuck,
      nullptr, common.stuck_exit_s > 0 ? service->GuardHeartbeat() : cli::Heartbeat{});
  service->AttachGuard(guard.get());
  signals.Watch(service.get());
  cli::ExitCode code;
  try {
    code = service->run();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    code = cli::ExitCode::kRuntimeError;
  }
  guard->Phase("the deletion of its DDS entities and devices");
  guard->Stopping();
  if (signals.signal() != 0) spdlog::info("stopped on signal {}", signals.signal());
  signals.Unwatch();
  service.reset();  // entities before participant, before the watcher goes
  guard.reset();
  return cli::ToInt(code);
}

}  // namespace dpc::services
