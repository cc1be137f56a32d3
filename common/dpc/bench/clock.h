#pragma once
// Wall-clock and monotonic readings in nanoseconds, as the bench's messages carry them
// (*_time_ns fields), and an absolute sleep for paced loops.

#include <time.h>

#include <cerrno>
#include <chrono>
#include <cstdint>

namespace dpc {

/// CLOCK_REALTIME: comparable across the processes of one host (loop latency).
inline int64_t WallClockNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// CLOCK_MONOTONIC: for timeouts inside one process.
inline int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// Sleeps until MonotonicNs() reaches `monotonic_ns` (absolute, so periods do not drift;
/// resumed after signals). Pair with PR_SET_TIMERSLACK for sub-50-µs accuracy.
inline void SleepUntilMonotonicNs(int64_t monotonic_ns) {
  const timespec ts{static_cast<time_t>(monotonic_ns / 1000000000), static_cast<long>(monotonic_ns % 1000000000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace dpc
