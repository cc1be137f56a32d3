#include "dpc/bus/recorded_bench.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/topics.h"
#include "dpc/record/mcap.h"

namespace dpc::bus {
namespace {

namespace fs = std::filesystem;

/// Writes a recording as dpc record would: a channel per topic, each message its payload.
class RecordingWriter {
 public:
  explicit RecordingWriter(const fs::path& path) : writer_(path.string(), {"test", record::McapCompression::kNone, 4096}) {
    const uint16_t schema = writer_.AddSchema("dpc::msg::any", "omgidl", "");
    for (const char* topic : {"dpc_stokes_sample", "dpc_waveplate_state", "dpc_device_description", "dpc_target"}) {
      channels_[topic] = writer_.AddChannel(schema, topic, "cdr", {});
    }
  }
  void Add(const std::string& topic, uint64_t log_time_ns, std::string bytes) {
    writer_.Write({channels_.at(topic), ++sequence_, log_time_ns, log_time_ns, std::move(bytes)});
  }
  void Sample(uint64_t log_time_ns, uint64_t sequence, int64_t time_ns, const StokesVector& s_in) {
    BenchSample s;
    s.sequence = sequence;
    s.time_ns = time_ns;
    s.s_in = s_in;
    s.s_out = StokesVector::UnitZ();
    msg::StokesSample m;
    WriteSample(s, "bench7", &m);
    Add("dpc_stokes_sample", log_time_ns, EncodeRaw(m));
  }
  void State(uint64_t log_time_ns, uint64_t answers, double phi0, DriverMode mode = DriverMode::kActive) {
    DriverState s;
    s.answers_sample = answers;
    s.motion = WaveplateMotion::Still(ControlVector::Constant(3, phi0));
    s.mode = mode;
    msg::WaveplateState m;
    WriteState(s, "bench7", &m);
    Add("dpc_waveplate_state", log_time_ns, EncodeRaw(m));
  }
  record::McapWriter& writer() { return writer_; }

 private:
  record::McapWriter writer_;
  std::map<std::string, uint16_t> channels_;
  uint32_t sequence_ = 0;
};

class RecordedBenchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dpc_recorded_bench_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

StokesVector Sop(double angle_rad) { return StokesVector(std::cos(angle_rad), std::sin(angle_rad), 0.0); }

TEST_F(RecordedBenchTest, ReadsOneRunOfCheckedSamplesStatesAndTheDeviceInLogTimeOrder) {
  const fs::path file = dir_ / "session.mcap";
  {
    RecordingWriter w(file);
    DeviceDescription device;
    device.driver_id = "driver";
    device.stages.resize(3);
    device.stages[1].axis = Vector3::UnitZ();
    w.Add("dpc_device_description", 1'000, EncodeRaw(DeviceMessage(device, "bench7")));
    BenchTarget target;
    target.revision = 5;
    w.Add("dpc_target", 1'000, EncodeRaw(TargetMessage(target, "bench7")));
    // Samples 1..10 every 1 ms of bench time, sample 6 missing; a state after each.
    for (uint64_t n = 1; n <= 10; ++n) {
      if (n == 6) continue;
      w.Sample(1'000'000 * n, n, static_cast<int64_t>(n) * 1'000'000, Sop(0.1 * static_cast<double>(n)));
      w.State(1'000'000 * n + 300'000, n, 0.01 * static_cast<double>(n));
    }
    // A non-unit sample and a state with the wrong control count: rejected.
    msg::StokesSample bad;
    WriteSample(BenchSample{}, "bench7", &bad);
    bad.s_in()[0] = 2.0;
    w.Add("dpc_stokes_sample", 10'500'000, EncodeRaw(bad));
    DriverState two;
    two.motion = WaveplateMotion::Still(ControlVector::Zero(2));
    msg::WaveplateState two_message;
    WriteState(two, "bench7", &two_message);
    w.Add("dpc_waveplate_state", 10'600'000, EncodeRaw(two_message));
    // A restarted bench: sequence 1 again.
    w.Sample(11'000'000, 1, 1'000'000, Sop(3.0));
    w.Sample(12'000'000, 2, 2'000'000, Sop(3.1));
    w.writer().WriteMetadata({"scenario", {{"text", "name: \"x\""}}});
  }
  const RecordedBench r = ReadRecordedBench(file.string());
  EXPECT_TRUE(r.complete) << r.problem;
  EXPECT_EQ(r.bench_id, "bench7");
  ASSERT_EQ(r.samples.size(), 9u);
  EXPECT_EQ(r.samples.front().sequence, 1u);
  EXPECT_EQ(r.samples.back().sequence, 10u);
  EXPECT_EQ(r.samples_missing, 1u);
  EXPECT_TRUE(r.later_runs);
  EXPECT_NEAR(r.SampleRateHz(), 1000.0, 1e-9);
  ASSERT_TRUE(r.device.has_value());
  EXPECT_EQ(r.controls, 3);
  ASSERT_EQ(r.states.size(), 9u);
  EXPECT_EQ(r.states[2].answers_sample, 3u);
  EXPECT_DOUBLE_EQ(r.state_phi[r.states[2].phi_offset + 2], 0.03);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].target.revision, 5u);
  EXPECT_EQ(r.rejected, 2u);
  EXPECT_EQ(r.metadata.at("scenario").at("text"), "name: \"x\"");

  // The input: one SOP per sample of the run, the missing one filled with the one before.
  const RecordedInput input = r.Input();
  ASSERT_EQ(input.sops.size(), 10u);
  EXPECT_TRUE(input.sops[5].isApprox(Sop(0.5)));
  EXPECT_TRUE(input.sops[6].isApprox(Sop(0.7)));
  EXPECT_EQ(input.source, file.string());
}

TEST_F(RecordedBenchTest, AWindowOfBenchTimeAndSamplesOnly) {
  const fs::path file = dir_ / "window.mcap";
  {
    RecordingWriter w(file);
    for (uint64_t n = 1; n <= 100; ++n) {
      w.Sample(1'000'000 * n, n, static_cast<int64_t>(n) * 1'000'000, Sop(0.01 * static_cast<double>(n)));
      w.State(1'000'000 * n + 1, n, 0.0);
    }
  }
  RecordedBenchOptions options;
  options.from_s = 0.010;
  options.duration_s = 0.020;
  options.samples_only = true;
  const RecordedBench r = ReadRecordedBench(file.string(), options);
  ASSERT_EQ(r.samples.size(), 20u);
  EXPECT_EQ(r.samples.front().sequence, 11u);
  EXPECT_EQ(r.samples.back().sequence, 30u);
  EXPECT_FALSE(r.later_runs);
  EXPECT_TRUE(r.states.empty());
  options.from_s = -1.0;
  EXPECT_THROW(ReadRecordedBench(file.string(), options), std::invalid_argument);
}

TEST_F(RecordedBenchTest, WhatIsNotARecordingIsAnError) {
  const fs::path file = dir_ / "not.mcap";
  { std::ofstream(file) << "hello"; }
  EXPECT_THROW(ReadRecordedBench(file.string()), std::runtime_error);
  EXPECT_THROW(ReadRecordedBench((dir_ / "missing.mcap").string()), std::runtime_error);
}

}  // namespace
}  // namespace dpc::bus
