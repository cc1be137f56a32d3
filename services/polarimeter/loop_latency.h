#pragma once
// The loop's latency as the bench sees it, from the driver's states alone: a state that applies
// a new command carries the answered sample's publish time, the command's arrival at the driver
// and its own publish time (CLOCK_REALTIME, comparable on one host); the bench adds the time
// the state reached it. Three spans per answered sample:
//
//   sample published → command received by the driver   (two hops and the controller's update)
//   sample published → state published by the driver    (+ the driver's validation and apply)
//   sample published → state received by the bench      (the whole loop, three hops)
//
// Recorded in fixed-size histograms (LogHistogram, 0.4 % bins): O(1) per state, no allocation
// after construction, no growth over any run length. Not counted: states that repeat an
// answered sample (the driver's hold and switch notices, lockstep re-answers), states that
// answer a sample published before the recorder started (a previous bench run's, repeated by
// the driver's heartbeat), and spans that are negative or longer than 10 s (clocks of
// different hosts).

#include <cstdint>

#include <nlohmann/json.hpp>

#include "dpc/bench/bench_messages.h"
#include "dpc/sim/log_histogram.h"

namespace dpc::services {

class LoopLatencyRecorder {
 public:
  /// Counts states answering samples published at or after `since_wall_ns` (CLOCK_REALTIME).
  explicit LoopLatencyRecorder(int64_t since_wall_ns = 0);

  /// One received state, `receive_wall_ns` its arrival (CLOCK_REALTIME). Not thread-safe.
  void OnState(const DriverState& state, int64_t receive_wall_ns);

  /// Per span: count, p50, p99, p99.9 and max in µs (null percentiles when empty).
  nlohmann::ordered_json Json() const;

  const LogHistogram& to_driver_us() const { return to_driver_us_; }
  const LogHistogram& to_state_published_us() const { return to_state_published_us_; }
  const LogHistogram& to_state_received_us() const { return to_state_received_us_; }
  /// States skipped because a span was negative or over 10 s.
  uint64_t implausible() const { return implausible_; }

 private:
  int64_t since_wall_ns_;
  uint64_t last_answered_ = 0;
  uint64_t implausible_ = 0;
  LogHistogram to_driver_us_, to_state_published_us_, to_state_received_us_;
};

}  // namespace dpc::services
