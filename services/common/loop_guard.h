#pragma once
// A service that is stuck says so and exits, rather than hang unseen. The main thread of every
// service runs a loop that never waits long (the driver's ticks, the polarimeter's samples, the
// controller's statuses, the emulator's polls) and counts each turn (Turn). A guard thread looks
// at the count a few times a second:
//
//   - the loop has not turned for the turn limit (--stuck-exit-s, raised to what the service's
//     own bounded waits need, Service::LongestTurnS): a call that does not return — Fast DDS
//     2.9 can deadlock inside a secured participant and block the thread that deletes a reader;
//     a trace written into a pipe nobody reads — holds the loop;
//   - the service was asked to stop (SIGINT, SIGTERM, or its run ended) and has not ended
//     within the stop grace: run() or the deletion of its DDS entities does not return.
//
// Then it logs why (what the loop was doing: Phase) and the process exits at once with code 1
// (cli::ExitCode::kRuntimeError), so that a supervisor (compose's restart policy, systemd)
// restarts it; a driver restarted so starts from the waveplates' read-back φ.
//
// A process stopped as a whole (SIGSTOP, a suspended machine) is not stuck: when the guard
// itself has not run for kPauseNs, it starts its windows again.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

namespace dpc::services {

/// What the guard decides, without threads or clocks: one Look at a time.
class StuckJudge {
 public:
  /// The guard looking no more often than this means it was not running itself.
  static constexpr int64_t kPauseNs = 2'000'000'000;

  /// `turn_limit_ns` 0: the loop is not judged (the stop grace still is).
  StuckJudge(int64_t turn_limit_ns, int64_t stop_grace_ns)
      : turn_limit_ns_(turn_limit_ns), stop_grace_ns_(stop_grace_ns) {}

  /// One look at monotonic `now_ns`: `turns` counted so far, whether a stop was asked, what the
  /// loop is doing. Returns why the process should end now, or "".
  std::string Look(int64_t now_ns, uint64_t turns, bool stopping, std::string_view phase);

 private:
  int64_t turn_limit_ns_;
  int64_t stop_grace_ns_;
  bool looked_ = false;
  int64_t last_look_ns_ = 0;
  uint64_t turns_ = 0;
  int64_t turned_ns_ = 0;       ///< when the count last changed (as seen by the looks)
  int64_t stop_seen_ns_ = -1;   ///< when a stop was first seen (-1: none yet)
};

class LoopGuard {
 public:
  using OnStuck = std::function<void(const std::string& why)>;
  static constexpr int64_t kLookPeriodNs = 100'000'000;
  static constexpr double kStopGraceS = 8.0;  ///< below compose's 10-s stop_grace_period

  /// Starts the guard's thread. `turn_limit_s` 0: the loop is not judged. `on_stuck` (called once,
  /// from the guard's thread) defaults to ExitStuck.
  LoopGuard(double turn_limit_s, double stop_grace_s, OnStuck on_stuck = ExitStuck);
  ~LoopGuard();
  LoopGuard(const LoopGuard&) = delete;
  LoopGuard& operator=(const LoopGuard&) = delete;

  /// One turn of the loop (any thread; a relaxed increment).
  void Turn() noexcept { turns_.fetch_add(1, std::memory_order_relaxed); }
  /// What the loop does now, for the message: a string literal (it is kept by pointer).
  void Phase(const char* literal) noexcept { phase_.store(literal, std::memory_order_relaxed); }
  /// A stop was asked, or run() ended: the process must end within the stop grace.
  void Stopping() noexcept { stopping_.store(true, std::memory_order_relaxed); }

  /// Logs `why` (critical; given at most 1 s, in case the log's own sink is what blocks) and
  /// ends the process at once with code 1, without destructors or exit handlers.
  [[noreturn]] static void ExitStuck(const std::string& why);

 private:
  void Watch();

  StuckJudge judge_;
  OnStuck on_stuck_;
  std::atomic<uint64_t> turns_{0};
  std::atomic<const char*> phase_{"its loop"};
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quitting_ = false;
  std::thread thread_;
};

}  // namespace dpc::services
