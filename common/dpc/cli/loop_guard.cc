#include "dpc/cli/loop_guard.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <memory>
#include <utility>

#include <fmt/format.h>

namespace dpc::cli {

std::string StuckJudge::Look(int64_t now_ns, uint64_t turns, bool stopping, std::string_view phase) {
  if (!looked_ || now_ns - last_look_ns_ >= kPauseNs) {
    // The first look, or the guard itself was not running (the whole process stopped, the
    // machine suspended): what the loop did meanwhile cannot be told; the windows start now.
    looked_ = true;
    turns_ = turns;
    turned_ns_ = now_ns;
    window_ns_ = now_ns;
    if (stop_seen_ns_ >= 0) stop_seen_ns_ = now_ns;
  }
  last_look_ns_ = now_ns;
  if (turns != turns_) {
    turns_ = turns;
    turned_ns_ = now_ns;
  }
  if (stopping) {
    if (stop_seen_ns_ < 0) stop_seen_ns_ = now_ns;
    if (now_ns - stop_seen_ns_ >= stop_grace_ns_) {
      return fmt::format("did not end within {:.1f} s of being asked to stop (stuck in: {}); exiting with code 1, "
                         "without cleaning up",
                         static_cast<double>(now_ns - stop_seen_ns_) * 1e-9, phase);
    }
    return {};
  }
  if (turn_limit_ns_ > 0 && now_ns - turned_ns_ >= turn_limit_ns_) {
    return fmt::format("stuck: its loop has not turned for {:.1f} s (stuck in: {}), most likely in a call that "
                       "does not return; exiting with code 1 so that a supervisor restarts it (--stuck-exit-s)",
                       static_cast<double>(now_ns - turned_ns_) * 1e-9, phase);
  }
  return {};
}

std::string StuckJudge::LookAtBeat(int64_t now_ns, std::optional<int64_t> beat_ns, int64_t limit_ns,
                                   std::string_view what) const {
  if (!beat_ns || limit_ns <= 0 || !looked_) return {};
  const int64_t silent_ns = now_ns - std::max(*beat_ns, window_ns_);
  if (silent_ns < limit_ns) return {};
  return fmt::format("stuck: {} has not run for {:.1f} s though its loop turns; exiting with code 1 so that a "
                     "supervisor restarts it",
                     what, static_cast<double>(silent_ns) * 1e-9);
}

LoopGuard::LoopGuard(double turn_limit_s, double stop_grace_s, OnStuck on_stuck,
                     std::function<bool()> stop_requested, Heartbeat heartbeat)
    : judge_(static_cast<int64_t>(turn_limit_s * 1e9), static_cast<int64_t>(stop_grace_s * 1e9)),
      on_stuck_(std::move(on_stuck)),
      stop_requested_(std::move(stop_requested)),
      heartbeat_(std::move(heartbeat)) {
  thread_ = std::thread([this] { Watch(); });
}

LoopGuard::~LoopGuard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quitting_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void LoopGuard::Watch() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, std::chrono::nanoseconds(kLookPeriodNs), [this] { return quitting_; })) {
    const int64_t now_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
            .count();
    const bool stopping = stopping_.load(std::memory_order_relaxed) || (stop_requested_ && stop_requested_());
    std::string why =
        judge_.Look(now_ns, turns_.load(std::memory_order_relaxed), stopping, phase_.load(std::memory_order_relaxed));
    if (why.empty() && !stopping && heartbeat_.latest_beat_ns) {
      why = judge_.LookAtBeat(now_ns, heartbeat_.latest_beat_ns(), static_cast<int64_t>(heartbeat_.limit_s * 1e9),
                              heartbeat_.what);
    }
    if (why.empty()) continue;
    lock.unlock();
    on_stuck_(why);
    return;  // once
  }
}

std::string StuckExitProblem(const std::string& text) {
  size_t used = 0;
  double seconds = 0.0;
  try {
    seconds = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(seconds == 0.0 || (seconds >= 1.0 && seconds <= 3600.0))) {
    return "must be 0 (off) or from 1 to 3600 s, not " + text;
  }
  return {};
}

void ExitAfterSaying(std::function<void()> say, int code) {
  auto said = std::make_shared<std::atomic<bool>>(false);
  std::thread([say = std::move(say), said] {
    say();
    said->store(true);
  }).detach();
  for (int i = 0; i < 100 && !said->load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  _exit(code);
}

}  // namespace dpc::cli
