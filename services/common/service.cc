#include "service.h"

#include <algorithm>
#include <csignal>

namespace dpc::services {
namespace {

/// SIGINT and SIGTERM stop the service, SIGHUP asks it to reload its participant; SIGUSR1 (sent
/// by the watcher's destructor to its own thread) ends the watcher.
sigset_t WatchedSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  sigaddset(&set, SIGUSR1);
  return set;
}

}  // namespace

void Service::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_.exchange(true)) return;
  }
  if (guard_ != nullptr) guard_->Stopping();
  stop_requested_.notify_all();
  OnStop();
}

bool Service::WaitForStopUntil(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  return stop_requested_.wait_until(lock, deadline, [this] { return stopped(); });
}

void ExitStuck(const std::string& why) {
  cli::ExitAfterSaying(
      [why] {
        spdlog::critical("{}", why);
        spdlog::default_logger()->flush();
      },
      cli::ToInt(cli::ExitCode::kRuntimeError));
}

double GuardedTurnLimitS(double option_s, std::optional<double> longest_turn_s) {
  if (option_s <= 0.0 || !longest_turn_s) return 0.0;
  constexpr double kMarginS = 2.0;
  return std::max(option_s, *longest_turn_s + kMarginS);
}

SignalWatcher::SignalWatcher() {
  const sigset_t set = WatchedSignals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  thread_ = std::thread([this] { Loop(); });
}

SignalWatcher::~SignalWatcher() {
  quitting_ = true;
  pthread_kill(thread_.native_handle(), SIGUSR1);
  thread_.join();
}

void SignalWatcher::Watch(Service* service) {
  std::lock_guard<std::mutex> lock(mutex_);
  service_ = service;
  if (signal_.load() != 0) service->stop();
}

void SignalWatcher::Unwatch() {
  std::lock_guard<std::mutex> lock(mutex_);
  service_ = nullptr;
}

void SignalWatcher::Loop() {
  const sigset_t set = WatchedSignals();
  for (;;) {
    int signal = 0;
    if (sigwait(&set, &signal) != 0) continue;
    if (signal == SIGUSR1) {
      if (quitting_.load()) return;
      continue;  // someone else's SIGUSR1: not ours to act on
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (signal == SIGHUP) {
      if (service_ != nullptr) {
        service_->RequestReload();
      } else {
        spdlog::warn("SIGHUP while no service runs: nothing to reload");
      }
      continue;
    }
    signal_ = signal;
    if (service_ != nullptr) service_->stop();
  }
}

}  // namespace dpc::services
