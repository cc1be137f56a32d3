// Writes the seed corpora of the message fuzz targets: a few valid messages of each type,
// serialized through the PubSubType the bus registers (the payload a reader receives).
//
//   dpc_fuzz_seeds <dir>     → <dir>/<target>/<name>.cdr
//
// Each seed is read back (fuzz::FromWire) and must pass its check: a seed the check refuses
// would only start the fuzzer off the path that matters.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_config.h"
#include "dpc/record/mcap.h"
#include "fuzz_wire.h"

namespace {

using namespace dpc;
namespace fs = std::filesystem;

fs::path root;

template <typename Message>
std::string Serialize(Message message) {
  typename bus::TopicTraits<Message>::PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&message)());
  if (!type.serialize(&message, &payload)) throw std::runtime_error("serialize failed");
  return std::string(reinterpret_cast<const char*>(payload.data), payload.length);
}

template <typename Message, typename Check>
void Seed(const std::string& target, const std::string& name, const Message& message, Check accepted) {
  const std::string bytes = Serialize(message);
  Message back;
  if (!fuzz::FromWire(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), &back) || !accepted(back)) {
    throw std::runtime_error("seed " + target + "/" + name + " does not read back as valid");
  }
  fs::create_directories(root / target);
  std::ofstream(root / target / (name + ".cdr"), std::ios::binary) << bytes;
}

/// A sequence number that makes the fuzz targets assume a device of `controls` controls.
uint64_t SequenceFor(int controls, uint64_t k) { return static_cast<uint64_t>(controls - 1) + kMaxControls * k; }

ControlVector Values(int n, double first, double step) {
  ControlVector v(n);
  for (int i = 0; i < n; ++i) v[i] = first + step * i;
  return v;
}

void Samples() {
  auto ok = [](const msg::StokesSample& m) { BenchSample s; return bus::ReadSample(m, &s).empty(); };
  BenchSample sample;
  sample.sequence = 1;
  sample.time_ns = 20'000;
  sample.publish_time_ns = 1'700'000'000'000'000'000;
  sample.s_in = StokesVector(1.0, 0.0, 0.0);
  sample.s_out = StokesVector(0.0, 0.6, 0.8);
  msg::StokesSample message;
  bus::WriteSample(sample, "bench", &message);
  Seed("read_sample", "plain", message, ok);
  sample.sequence = 42;
  sample.optical_power_w = 1e-3;
  sample.lockstep = true;
  sample.s_in = StokesVector(0.0, -1.0, 0.0);
  sample.s_out = StokesVector(1.0, 1.0, 1.0).normalized();
  bus::WriteSample(sample, "bench-with-a-longer-name", &message);
  Seed("read_sample", "power_lockstep", message, ok);
}

void Commands() {
  auto ok = [](const msg::WaveplateCommand& m) {
    ControllerCommand c;
    return bus::ReadCommand(m, fuzz::ControlCountFor(m.sequence_number()), &c).empty();
  };
  ControllerCommand command;
  command.controller_id = "primary";
  command.priority = 10;
  command.answers_sample = 41;
  command.sample_time_ns = 820'000;
  command.sample_publish_time_ns = command.publish_time_ns = 1'700'000'000'000'000'000;
  msg::WaveplateCommand message;
  command.sequence = SequenceFor(3, 1);
  command.phi = Values(3, 0.1, 0.2);
  bus::WriteCommand(command, "bench", &message);
  Seed("read_command", "three_points", message, ok);
  command.sequence = SequenceFor(3, 2);
  command.rate_per_s = Values(3, -5.0, 2.5);
  bus::WriteCommand(command, "bench", &message);
  Seed("read_command", "three_ramps", message, ok);
  command.controller_id = "standby";
  command.sequence = SequenceFor(1, 3);
  command.phi = Values(1, 0.5, 0.0);
  command.rate_per_s = Values(1, 100.0, 0.0);
  bus::WriteCommand(command, "bench", &message);
  Seed("read_command", "one_ramp", message, ok);
  command.sequence = SequenceFor(16, 0);
  command.phi = Values(16, -1.0, 0.125);
  command.rate_per_s.resize(0);
  bus::WriteCommand(command, "bench", &message);
  Seed("read_command", "sixteen_points", message, ok);
}

void States() {
  auto ok = [](const msg::WaveplateState& m) {
    DriverState s;
    return bus::ReadState(m, fuzz::ControlCountFor(m.sequence_number()), &s).empty();
  };
  DriverState state;
  state.sequence = SequenceFor(3, 1);
  state.answers_sample = 41;
  state.sample_time_ns = 820'000;
  state.motion = WaveplateMotion::Still(Values(3, 0.1, 0.2));
  state.motion.start_ns = 840'000;
  state.motion.end_ns = 840'000;
  state.mode = DriverMode::kHolding;
  state.reason = "no controller";
  msg::WaveplateState message;
  bus::WriteState(state, "bench", &message);
  Seed("read_state", "holding", message, ok);
  state.sequence = SequenceFor(3, 2);
  state.mode = DriverMode::kActive;
  state.reason = "";
  state.obeyed_controller_id = "primary";
  state.obeyed_priority = 10;
  state.motion.rate_per_s = Values(3, -5.0, 2.5);
  state.motion.end_ns = 840'000 + 20'000;
  state.motion.moving = true;
  state.saturated[1] = true;
  state.commands_applied = 40;
  state.commands_rejected = 1;
  state.commands_limited = 2;
  state.controller_switches = 1;
  state.last_rejection = "phi[0] = nan is not finite";
  bus::WriteState(state, "bench", &message);
  Seed("read_state", "ramping", message, ok);
}

void Statuses() {
  auto ok = [](const msg::ControllerStatus& m) {
    ControllerStatusReport s;
    return bus::ReadStatus(m, &s).empty();
  };
  ControllerStatusReport status;
  status.controller_id = "main";
  status.priority = 10;
  status.law = "gp";
  status.condition = "waiting for samples";
  Seed("read_status", "waiting", bus::StatusMessage(status, "bench"), ok);
  status.obeyed = true;
  status.condition = "tracking (predicting 0.200 ms ahead, input at 120 rad/s)";
  status.answers_sample = 123456;
  status.error_deg = 0.8;
  status.sigma_max = 1.9;
  status.sigma_min = 0.7;
  status.nullspace_active_fraction = 1.0;
  status.compute_time_mean_s = 1.2e-6;
  status.compute_time_max_s = 9e-6;
  status.updates = 123456;
  status.missed_deadlines = 2;
  status.last_rejection = "sample 17: a non-unit S_in (|S| = 1.2)";
  status.publish_time_ns = 1'700'000'000'000'000'000;
  Seed("read_status", "tracking", bus::StatusMessage(status, "bench"), ok);
}

void Summaries() {
  auto ok = [](const msg::BenchSummary& m) {
    BenchSummary s;
    return bus::ReadSummary(m, &s).empty();
  };
  BenchSummary summary;
  summary.sequence = 1;
  summary.publish_time_ns = 1'700'000'000'000'000'000;
  summary.period_s = 0.05;
  msg::BenchSummary message;
  bus::WriteSummary(summary, "bench", &message);
  Seed("read_summary", "nothing_yet", message, ok);
  summary.sequence = 2;
  summary.samples = 500;
  summary.last_sample = 1000;
  summary.s_in = StokesVector(0.0, 1.0, 0.0);
  summary.s_out = StokesVector(0.0, 0.6, 0.8);
  summary.trail = {{1, 0, 0, 0, 0.6, 0.8}, {0, 1, 0, 0, 0.8, 0.6}};
  summary.error_mean_deg = 1.5;
  summary.error_max_deg = 3.0;
  summary.latencies = 500;
  summary.latency_p50_us = 200;
  summary.latency_p90_us = 300;
  summary.latency_p99_us = 900;
  summary.latency_max_us = 2000;
  DriverState state;
  state.motion = WaveplateMotion::Still(Values(3, 0.1, 0.2));
  state.mode = DriverMode::kActive;
  state.obeyed_controller_id = "main";
  state.saturated[2] = true;
  summary.state = state;
  bus::WriteSummary(summary, "bench", &message);
  Seed("read_summary", "locked", message, ok);
}

ControlMapConfig Polynomial() {
  ControlMapConfig map;
  map.kind = ControlMapConfig::Kind::kPolynomial;
  map.coefficients_rad = {0.1, 3.0, -0.2, 0.01};
  return map;
}

ControlMapConfig Table() {
  ControlMapConfig map;
  map.kind = ControlMapConfig::Kind::kTable;
  map.table_control = {-1.0, 0.0, 0.5, 1.0};
  map.table_angle_rad = {-3.0, 0.0, 1.4, 3.2};
  return map;
}

void Devices() {
  auto ok = [](const msg::DeviceDescription& m) { DeviceDescription d; return bus::ReadDevice(m, &d).empty(); };
  DeviceDescription device;
  device.driver_id = "driver-1";
  device.stages = PaperScenario("131").stages;
  Seed("read_device", "paper_131", bus::DeviceMessage(device, "bench"), ok);

  device.max_slew_per_s = 50.0;
  device.max_ramp_s = 0.01;
  device.stages = PaperScenario("3131").stages;
  device.stages[0].map = Polynomial();
  device.stages[1].map = Table();
  device.stages[1].range = ControlRange{-1.0, 1.0};
  device.stages[2].axis = Vector3(1.0, 1.0, 0.0);
  Seed("read_device", "maps_ranges", bus::DeviceMessage(device, "bench"), ok);

  StageConfig adjustable;
  adjustable.kind = StageConfig::Kind::kAdjustableAxis;
  adjustable.name = "lcvr";
  adjustable.retardance.controlled = true;
  adjustable.retardance.map = Table();
  adjustable.retardance.range = ControlRange{-1.0, 1.0};
  adjustable.orientation.controlled = true;
  adjustable.orientation.map = Polynomial();
  StageConfig half_wave = adjustable;
  half_wave.name = "rotating_half_wave";
  half_wave.retardance.controlled = false;
  half_wave.retardance.fixed_rad = M_PI;
  device.stages = {adjustable, half_wave, PaperScenario("1").stages[0]};
  Seed("read_device", "adjustable", bus::DeviceMessage(device, "bench"), ok);
}

void Targets() {
  auto ok = [](const msg::Target& m) { BenchTarget t; return bus::ReadTarget(m, &t).empty(); };
  BenchTarget target;
  target.revision = 1;
  Seed("read_target", "point", bus::TargetMessage(target, "bench"), ok);
  target.revision = 7;
  target.request_id = "req-7";
  target.target.kind = TargetConfig::Kind::kSet;
  target.target.normal = Vector3(0.0, 0.0, 2.0);
  target.target.offset = 0.5;
  Seed("read_target", "set", bus::TargetMessage(target, "bench"), ok);
}

void Requests() {
  auto ok = [](const msg::TargetRequest& m) {
    try {
      bus::TargetFromRequest(m);
      return true;
    } catch (const std::invalid_argument&) {
      return false;
    }
  };
  msg::TargetRequest request;
  request.bench_id("bench");
  request.request_id("req-1");
  request.kind(msg::TARGET_POINT);
  request.point({0.0, 0.6, 0.8});
  request.normal({0.0, 0.0, 1.0});
  Seed("target_request", "point", request, ok);
  request.request_id("req-2");
  request.kind(msg::TARGET_SET);
  request.normal({1.0, 1.0, 0.0});
  request.offset(-0.3);
  Seed("target_request", "set", request, ok);
}

/// Small recordings in each compression, and one cut short (a recorder killed mid-chunk).
void McapFiles() {
  fs::create_directories(root / "read_mcap");
  for (const record::McapCompression compression :
       {record::McapCompression::kNone, record::McapCompression::kZstd, record::McapCompression::kLz4}) {
    const std::string name = *record::McapCompressionName(compression) ? record::McapCompressionName(compression) : "none";
    const std::string path = (root / "read_mcap" / (name + ".mcap")).string();
    {
      record::McapWriter writer(path, {"seed", compression, 256});
      const uint16_t schema = writer.AddSchema("dpc::msg::StokesSample", "omgidl", "struct S { double x; };");
      const uint16_t channel = writer.AddChannel(schema, "dpc_stokes_sample", "cdr", {{"k", "v"}});
      writer.WriteMetadata({"scenario", {{"text", "name: \"seed\""}}});
      for (uint32_t k = 0; k < 40; ++k) writer.Write({channel, k, 1000 + k, 900 + k, std::string(8 + k % 5, static_cast<char>(k))});
      writer.Close();
    }
    if (compression == record::McapCompression::kZstd) {
      std::ifstream in(path, std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      std::ofstream(root / "read_mcap" / "zstd-cut.mcap", std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
    }
  }
}

/// Lines as the instruments and their clients write them: replies for instrument_reply (the
/// first byte picks one SOP or two and the lowest degree of polarization), protocol lines for
/// emulator_protocol (the first byte picks the EPC, the polarimeter or the control port).
void InstrumentTexts() {
  const auto write = [](const std::string& target, const std::string& name, const std::string& bytes) {
    fs::create_directories(root / target);
    std::ofstream(root / target / name, std::ios::binary) << bytes;
  };
  write("instrument_reply", "sop", std::string(1, '\x00') + "0.000000,0.600000,0.800000");
  write("instrument_reply", "both", std::string(1, '\x01') + "1,0,0, 0,0,-0.5");
  write("instrument_reply", "volts", std::string(1, '\x00') + "1.250000");
  write("emulator_protocol", "epc", std::string(1, '\x00') + "*IDN?\n:SOUR1:VOLT 1.5\n:SOUR2:VOLT?\n");
  write("emulator_protocol", "polarimeter", std::string(1, '\x01') + ":MEAS:SOP?\r\n:MEAS:BOTH?\n:MEAS:SIN?\n");
  write("emulator_protocol", "control",
        std::string(1, '\x02') + "garbage epc 2\nslow polarimeter 0.1 3\ntemperature 40\npowercycle 0.2\nstatus\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <seed directory>\n", argv[0]);
    return 2;
  }
  root = argv[1];
  try {
    Samples();
    Commands();
    States();
    Devices();
    Targets();
    Requests();
    Summaries();
    Statuses();
    McapFiles();
    InstrumentTexts();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dpc_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
