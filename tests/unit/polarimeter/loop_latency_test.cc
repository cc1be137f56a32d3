// LoopLatencyRecorder: the bench's view of the loop latency, from the driver's states.
#include "loop_latency.h"

#include <gtest/gtest.h>

#include <limits>

namespace dpc::services {
namespace {

constexpr int64_t kOrigin = 1'700'000'000'000'000'000;

DriverState State(uint64_t answers, int64_t to_driver_ns, int64_t to_published_ns) {
  DriverState state;
  state.answers_sample = answers;
  state.sample_publish_time_ns = kOrigin;
  state.command_receive_time_ns = kOrigin + to_driver_ns;
  state.publish_time_ns = kOrigin + to_published_ns;
  return state;
}

TEST(LoopLatencyRecorder, RecordsTheThreeSpansOfEachNewlyAnsweredSampleInMicroseconds) {
  LoopLatencyRecorder recorder;
  recorder.OnState(State(1, 100'000, 110'000), kOrigin + 150'000);
  EXPECT_EQ(recorder.to_driver_us().count(), 1);
  EXPECT_DOUBLE_EQ(recorder.to_driver_us().max(), 100.0);
  EXPECT_DOUBLE_EQ(recorder.to_state_published_us().max(), 110.0);
  EXPECT_DOUBLE_EQ(recorder.to_state_received_us().max(), 150.0);
  const auto json = recorder.Json();
  EXPECT_EQ(json["sample_to_state_received"]["count"].get<int64_t>(), 1);
  EXPECT_NEAR(json["sample_to_state_received"]["p50"].get<double>(), 150.0, 150.0 * 0.004);
}

TEST(LoopLatencyRecorder, IgnoresRepeatedAndOlderAnswersAndHeartbeatsWithoutASample) {
  LoopLatencyRecorder recorder;
  recorder.OnState(State(5, 100'000, 110'000), kOrigin + 150'000);
  recorder.OnState(State(5, 100'000, 110'000), kOrigin + 900'000);   // a hold notice repeats it
  recorder.OnState(State(4, 100'000, 110'000), kOrigin + 900'000);   // late, reordered
  DriverState heartbeat;                                      // before any command
  recorder.OnState(heartbeat, kOrigin);
  EXPECT_EQ(recorder.to_state_received_us().count(), 1);
  EXPECT_DOUBLE_EQ(recorder.to_state_received_us().max(), 150.0);
}

TEST(LoopLatencyRecorder, IgnoresAnswersToSamplesFromBeforeItStarted) {
  // A restarted bench numbers its samples from 1 again; the driver's heartbeat still repeats
  // the previous run's last command (sample 3000, published before this run).
  LoopLatencyRecorder recorder(kOrigin);
  DriverState previous_run = State(3000, 100'000, 110'000);
  previous_run.sample_publish_time_ns = kOrigin - 400'000'000;
  recorder.OnState(previous_run, kOrigin + 1'000);
  recorder.OnState(State(1, 100'000, 110'000), kOrigin + 150'000);
  recorder.OnState(State(2, 100'000, 110'000), kOrigin + 150'000);
  EXPECT_EQ(recorder.to_state_received_us().count(), 2);
  EXPECT_DOUBLE_EQ(recorder.to_state_received_us().max(), 150.0);
  EXPECT_EQ(recorder.implausible(), 0u);
}

TEST(LoopLatencyRecorder, SkipsAndCountsSpansThatCannotBeLatencies) {
  LoopLatencyRecorder recorder;
  recorder.OnState(State(1, -5'000, 110'000), kOrigin + 150'000);         // another host's clock
  recorder.OnState(State(2, 100'000, 110'000), kOrigin + 20'000'000'000);  // 20 s: a stale state
  DriverState forged = State(3, 0, 0);
  forged.command_receive_time_ns = std::numeric_limits<int64_t>::min();   // overflows a difference
  recorder.OnState(forged, kOrigin);
  EXPECT_EQ(recorder.implausible(), 3u);
  EXPECT_EQ(recorder.to_driver_us().count(), 0);
  const auto json = recorder.Json();
  EXPECT_TRUE(json["sample_to_command_at_driver"]["p50"].is_null());
  EXPECT_EQ(json["implausible"].get<uint64_t>(), 3u);
}

TEST(LoopLatencyRecorder, PercentilesFollowTheDistribution) {
  LoopLatencyRecorder recorder;
  for (uint64_t k = 1; k <= 1000; ++k) {
    const int64_t loop_ns = static_cast<int64_t>(k) * 1'000;  // 1 … 1000 µs
    recorder.OnState(State(k, loop_ns / 2, loop_ns / 2 + 1'000), kOrigin + loop_ns);
  }
  const auto json = recorder.Json()["sample_to_state_received"];
  EXPECT_EQ(json["count"].get<int64_t>(), 1000);
  EXPECT_NEAR(json["p50"].get<double>(), 500.0, 500.0 * 0.004);
  EXPECT_NEAR(json["p99"].get<double>(), 990.0, 990.0 * 0.004);
  EXPECT_DOUBLE_EQ(json["max"].get<double>(), 1000.0);
}

}  // namespace
}  // namespace dpc::services
