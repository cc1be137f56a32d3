#include "loop_guard.h"

#include <unistd.h>

#include <chrono>
#include <memory>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "dpc/bench/clock.h"
#include "dpc/cli/exit_code.h"

namespace dpc::services {

std::string StuckJudge::Look(int64_t now_ns, uint64_t turns, bool stopping, std::string_view phase) {
  if (!looked_ || now_ns - last_look_ns_ >= kPauseNs) {
    // The first look, or the guard itself was not running (the whole process stopped, the
    // machine suspended): what the loop did meanwhile cannot be told; the windows start now.
    looked_ = true;
    turns_ = turns;
    turned_ns_ = now_ns;
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

LoopGuard::LoopGuard(double turn_limit_s, double stop_grace_s, OnStuck on_stuck)
    : judge_(static_cast<int64_t>(turn_limit_s * 1e9), static_cast<int64_t>(stop_grace_s * 1e9)),
      on_stuck_(std::move(on_stuck)) {
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
    const std::string why =
        judge_.Look(MonotonicNs(), turns_.load(std::memory_order_relaxed), stopping_.load(std::memory_order_relaxed),
                    phase_.load(std::memory_order_relaxed));
    if (why.empty()) continue;
    lock.unlock();
    on_stuck_(why);
    return;  // once
  }
}

void LoopGuard::ExitStuck(const std::string& why) {
  // The stuck thread may hold the log's sink (a stderr nobody reads): the line is written by a
  // thread of its own, and the process ends whether or not it could be.
  auto written = std::make_shared<std::atomic<bool>>(false);
  std::thread([why, written] {
    spdlog::critical("{}", why);
    spdlog::default_logger()->flush();
    written->store(true);
  }).detach();
  for (int i = 0; i < 100 && !written->load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  _exit(cli::ToInt(cli::ExitCode::kRuntimeError));
}

}  // namespace dpc::services
