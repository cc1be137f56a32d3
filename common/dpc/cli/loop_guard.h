#pragma once
// A program that is stuck says so and exits, rather than hang unseen. The main thread of every
// bench service and of `dpc record` runs a loop that never waits long (the driver's ticks, the
// polarimeter's samples, the controller's statuses, the emulator's polls, the recorder's
// drains) and counts each turn (Turn). A guard thread looks at the count ten times a second:
//
//   - the loop has not turned for the turn limit (--stuck-exit-s, raised to what the program's
//     own bounded waits need): a call that does not return — Fast DDS 2.9 can deadlock inside a
//     secured participant and block the thread that deletes a reader; a file written into a
//     pipe nobody reads — holds the loop;
//   - the program was asked to stop (SIGINT, SIGTERM, or its run ended) and has not ended
//     within the stop grace: its loop or the deletion of its DDS entities does not return;
//   - a heartbeat the program watches besides its loop (Heartbeat: the event threads of its DDS
//     participants, bus::EventThreadCanary) has not beaten for the heartbeat's limit, though the
//     loop turns: Fast DDS 2.9 can deadlock a secured participant's event thread while samples
//     still flow, and such a participant never discovers anyone again.
//
// Then `on_stuck` says why (what the loop was doing: Phase) and ends the process at once with
// code 1 (cli::ExitCode::kRuntimeError; ExitAfterSaying), so that a supervisor (compose's
// restart policy, systemd) restarts it; a driver restarted so starts from the waveplates'
// read-back φ.
//
// A process stopped as a whole (SIGSTOP, a suspended machine) is not stuck: when the guard
// itself has not run for kPauseNs, it starts its windows again.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

namespace dpc::cli {

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
  /// After Look, at the same `now_ns`: the heartbeat's latest beat (steady-clock ns; none: nothing
  /// to watch), judged against `limit_ns` from the later of the beat and the start of the looks'
  /// window (a pause of the guard restarts it); `what` names the heartbeat. Returns why the
  /// process should end now, or "".
  std::string LookAtBeat(int64_t now_ns, std::optional<int64_t> beat_ns, int64_t limit_ns, std::string_view what) const;

 private:
  int64_t turn_limit_ns_;
  int64_t stop_grace_ns_;
  bool looked_ = false;
  int64_t last_look_ns_ = 0;
  uint64_t turns_ = 0;
  int64_t turned_ns_ = 0;       ///< when the count last changed (as seen by the looks)
  int64_t window_ns_ = 0;       ///< when the looks' window began (the first look, or after a pause)
  int64_t stop_seen_ns_ = -1;   ///< when a stop was first seen (-1: none yet)
};

/// The check of --stuck-exit-s (the turn limit in seconds): "" if `text` is 0 (off) or from 1 to
/// 3600, else why not.
std::string StuckExitProblem(const std::string& text);

/// Runs `say` (a line for the log) on a thread of its own, gives it at most 1 s (the stuck thread
/// may hold the log's sink: a stderr nobody reads), then ends the process at once with `code`,
/// without destructors or exit handlers.
[[noreturn]] void ExitAfterSaying(std::function<void()> say, int code);

/// Something a LoopGuard watches besides the loop: `latest_beat_ns` (thread-safe, asked at each
/// look) gives the time of its latest beat (steady-clock ns), or none when there is nothing to
/// watch; no beat for `limit_s` ends the process. `what` names it in the message.
struct Heartbeat {
  std::function<std::optional<int64_t>()> latest_beat_ns;
  double limit_s = 0.0;
  std::string what;
};

class LoopGuard {
 public:
  using OnStuck = std::function<void(const std::string& why)>;
  static constexpr int64_t kLookPeriodNs = 100'000'000;
  static constexpr double kStopGraceS = 8.0;  ///< below compose's 10-s stop_grace_period

  /// Starts the guard's thread. `turn_limit_s` 0: the loop is not judged. `on_stuck` is called
  /// once, from the guard's thread (it normally ends the process: ExitAfterSaying).
  /// `stop_requested`, if given, is asked at each look too (a flag a signal handler sets).
  /// `heartbeat`, if it has a source, is judged while the program is not stopping.
  LoopGuard(double turn_limit_s, double stop_grace_s, OnStuck on_stuck, std::function<bool()> stop_requested = {},
            Heartbeat heartbeat = {});
  ~LoopGuard();
  LoopGuard(const LoopGuard&) = delete;
  LoopGuard& operator=(const LoopGuard&) = delete;

  /// One turn of the loop (any thread; a relaxed increment).
  void Turn() noexcept { turns_.fetch_add(1, std::memory_order_relaxed); }
  /// What the loop does now, for the message: a string literal (it is kept by pointer). Returns
  /// the phase it replaces.
  const char* Phase(const char* literal) noexcept { return phase_.exchange(literal, std::memory_order_relaxed); }
  /// A stop was asked, or run() ended: the process must end within the stop grace.
  void Stopping() noexcept { stopping_.store(true, std::memory_order_relaxed); }

 private:
  void Watch();

  StuckJudge judge_;
  OnStuck on_stuck_;
  std::function<bool()> stop_requested_;
  Heartbeat heartbeat_;
  std::atomic<uint64_t> turns_{0};
  std::atomic<const char*> phase_{"its loop"};
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quitting_ = false;
  std::thread thread_;
};

}  // namespace dpc::cli
