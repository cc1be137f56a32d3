#pragma once
// Wall-clock and monotonic readings in nanoseconds, as carried on the bus (*_time_ns fields).

#include <chrono>
#include <cstdint>

namespace dpc::bus {

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

}  // namespace dpc::bus
