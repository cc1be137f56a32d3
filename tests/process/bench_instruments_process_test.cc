// The bench against real-instrument backends: dpc-emulator (an EPC and a polarimeter speaking
// SCPI-like lines on 127.0.0.1 TCP and on pseudo-terminals) driven by dpc-driver's line backend
// and read by dpc-polarimeter's instrument source, with the controller between them over DDS
// (loopback, domains 150-153 and 160). Each fault the emulator injects (a disconnect, garbage, cut or
// slow replies, a power cycle) makes the driver hold the last good φ and say why; on recovery
// the device is set to that φ again and control resumes without a jump.

#include <gtest/gtest.h>
#include <signal.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "dpc/bench/clock.h"
#include "dpc/config/scenario_config.h"
#include "dpc/instrument/line_link.h"
#include "dpc/scenario_io/scenario_file.h"
#include "dpc/scenario_io/scenario_writer.h"
#include "support/bench_fixture.h"

namespace dpc::testing {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

class BenchInstrumentsTest : public BenchFixture {
 protected:
  /// Starts the emulator (its true device: deploy/scenarios/emulator_epc.pbtxt) and returns its
  /// start-up line: the ports and pseudo-terminals it serves.
  json StartEmulator(std::vector<std::string> args = {}) {
    std::vector<std::string> argv = {DPC_EMULATOR_BINARY, std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/emulator_epc.pbtxt",
                                     "--tcp-port-epc", "0", "--tcp-port-polarimeter", "0", "--control-port", "0"};
    argv.insert(argv.end(), args.begin(), args.end());
    emulator_log_ = dir_ + "/emulator.log";
    processes_.push_back(std::make_unique<Process>(argv, dir_ + "/emulator.out", emulator_log_));
    std::string first;
    EXPECT_TRUE(Eventually([&] {
      std::ifstream in(dir_ + "/emulator.out");
      return static_cast<bool>(std::getline(in, first)) && !first.empty() && first.back() == '}';
    }, 10s)) << Slurp(emulator_log_);
    const json ports = json::parse(first, nullptr, false);
    EXPECT_FALSE(ports.is_discarded()) << first;
    // (Its status is one long JSON line.)
    control_ = std::make_unique<instrument::LineLink>(Tcp(ports.value("control_tcp", 0)), 1 << 16);
    EXPECT_EQ(control_->Open(2.0), "");
    return ports;
  }

  static InstrumentLinkConfig Tcp(int port) {
    InstrumentLinkConfig link;
    link.port = port;
    link.response_timeout_s = 0.2;
    link.reconnect_min_s = 0.05;
    link.reconnect_max_s = 0.4;
    return link;
  }
  static InstrumentLinkConfig Serial(const std::string& path) {
    InstrumentLinkConfig link = Tcp(0);
    link.kind = InstrumentLinkConfig::Kind::kSerial;
    link.path = path;
    return link;
  }

  /// The bench's scenario: the emulator's device as the bench believes it (the same maps), the
  /// default bench's controller, the two instruments.
  std::string BenchScenario(const InstrumentLinkConfig& epc, const InstrumentLinkConfig& polarimeter) {
    ScenarioConfig scenario = LoadScenarioFile(std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/emulator_epc.pbtxt");
    scenario.controller.method = ControlMethod::kGradientProjection;
    scenario.controller.step = 0.5;
    scenario.controller.nullspace_step = 0.1;
    scenario.controller.loop = LoopMode::kModel;
    scenario.controller.activation_s = 0.0;
    WaveplateDeviceConfig device;
    device.link = epc;
    scenario.waveplate_device = device;
    PolarimeterDeviceConfig meter;
    meter.link = polarimeter;
    meter.reply = PolarimeterDeviceConfig::Reply::kOutput;
    scenario.polarimeter_device = meter;
    const std::string path = dir_ + "/bench.pbtxt";
    std::ofstream(path) << ScenarioToText(scenario);
    return path;
  }

  void StartBench(int domain, const std::string& scenario, int rate_hz = 500) {
    StartObserver(domain);
    StartDriver({scenario});
    controller_ = &StartController("A", 0, {scenario});
    StartPolarimeter({scenario, "--rate-hz", std::to_string(rate_hz), "--settle-samples", "0"});
  }

  /// A control-port command's reply.
  std::string Control(const std::string& command) {
    std::string why;
    const auto reply = control_->Query(command, 2.0, &why);
    return reply ? *reply : "(" + why + ")";
  }
  json Status() { return json::parse(Control("status"), nullptr, false); }

  bool Locked(std::chrono::milliseconds within = 20s) {
    return Eventually([&] {
      const int64_t now = WallClockNs();
      return Obeys("A") && MedianErrorDeg(now - 500'000'000, now) < 5.0;
    }, within);
  }

  /// Ends the test's participant and forgets what it saw (before another bench's observer).
  void StopObserver() {
    statuses_.reset();
    samples_.reset();
    states_.reset();
    participant_.reset();
    std::lock_guard<std::mutex> lock(mutex_);
    seen_.clear();
    sample_errors_.clear();
    statuses_seen_.clear();
  }

  /// Injects `fault` at the EPC and checks: the driver holds and says `because`, then resumes
  /// obeying the controller, and resuming is no bump: the output's error right after it does not
  /// rise above what the hold left (the first command corrects from the held φ).
  void ExpectHoldAndResume(const std::string& fault, const std::string& because) {
    ASSERT_TRUE(Locked()) << Logs();
    const size_t before = StateCount();
    ASSERT_EQ(Control(fault).rfind("OK", 0), 0u) << fault;
    ASSERT_TRUE(Eventually([&] {
      auto s = LatestState();
      return s && s->mode() == msg::DRIVER_HOLDING && s->reason().to_string().find(because) != std::string::npos;
    }, 5s)) << fault << ": " << (LatestState() ? LatestState()->reason().to_string() : "no state") << "\n" << Logs();
    ASSERT_TRUE(Eventually([&] { return Obeys("A"); }, 15s)) << fault << ": no resume\n" << Logs();
    std::this_thread::sleep_for(400ms);
    // The first active state after the hold: when control resumed (wall clock).
    const std::vector<SeenState> states = States();
    int64_t resumed_ns = 0;
    bool holding_seen = false;
    for (size_t i = before; i < states.size() && resumed_ns == 0; ++i) {
      const auto& s = states[i].state;
      if (s.mode() == msg::DRIVER_HOLDING) holding_seen = true;
      if (holding_seen && s.mode() == msg::DRIVER_ACTIVE) resumed_ns = s.publish_time_ns();
    }
    ASSERT_GT(resumed_ns, 0);
    const double at_resume = MaxErrorDeg(resumed_ns - 50'000'000, resumed_ns);
    const double after = MaxErrorDeg(resumed_ns, resumed_ns + 300'000'000);
    EXPECT_LE(after, at_resume + 2.0) << fault << ": the error rose from " << at_resume << "° to " << after
                                      << "° after resuming";
    EXPECT_TRUE(Locked(10s)) << fault << ": not locked again\n" << Logs();
  }

  std::vector<double> LatestPhi() {
    const auto s = LatestState();
    return s ? std::vector<double>(s->phi_applied().begin(), s->phi_applied().end()) : std::vector<double>{};
  }

  std::unique_ptr<instrument::LineLink> control_;
  Process* controller_ = nullptr;
  std::string emulator_log_;
};

TEST_F(BenchInstrumentsTest, TheBenchLocksThroughTheInstrumentsOverTcp) {
  const json ports = StartEmulator();
  StartBench(150, BenchScenario(Tcp(ports["epc_tcp"]), Tcp(ports["polarimeter_tcp"])));
  ASSERT_TRUE(Locked()) << Logs();
  // dpc monitor shows the bench as a person watches it: locked, obeying A.
  Process monitor({DPC_BINARY, "monitor", "--lines", "--duration-s", "2", "--domain", "150"}, dir_ + "/monitor.log");
  ASSERT_EQ(monitor.Wait(20s), 0) << monitor.Log();
  EXPECT_NE(monitor.Log().find("LOCKED"), std::string::npos) << monitor.Log();
  EXPECT_NE(monitor.Log().find("obeyed A"), std::string::npos) << monitor.Log();
  // The controller stops: the driver holds, and the device's channels hold exactly the φ it
  // reports (the DAC's voltages, sent with 4 decimals).
  controller_->Signal(SIGTERM);
  ASSERT_TRUE(Eventually([&] {
    const auto state = LatestState();
    return state && state->mode() == msg::DRIVER_HOLDING;
  }, 5s)) << Logs();
  std::this_thread::sleep_for(300ms);
  const std::vector<double> held = LatestPhi();
  const json channels = Status()["channels"];
  ASSERT_EQ(channels.size(), held.size()) << channels.dump();
  for (size_t i = 0; i < held.size(); ++i) {
    EXPECT_NEAR(channels[i]["set_v"].get<double>(), held[i], 1.5e-4) << "channel " << i + 1;
  }
}

TEST_F(BenchInstrumentsTest, TheBenchLocksThroughTheInstrumentsOverPseudoTerminals) {
  const json ports = StartEmulator({"--pty"});
  ASSERT_TRUE(ports.contains("epc_pty")) << ports.dump();
  StartBench(151, BenchScenario(Serial(ports["epc_pty"]), Serial(ports["polarimeter_pty"])));
  ASSERT_TRUE(Locked()) << Logs();
}

TEST_F(BenchInstrumentsTest, EveryFaultOfTheEpcHoldsTheLastGoodPhiAndResumesWithoutAJump) {
  const json ports = StartEmulator();
  StartBench(152, BenchScenario(Tcp(ports["epc_tcp"]), Tcp(ports["polarimeter_tcp"])));
  ExpectHoldAndResume("disconnect epc 1", "backend");
  ExpectHoldAndResume("garbage epc 3", "not \"OK\"");
  ExpectHoldAndResume("slow epc 0.5 2", "no reply");
  ExpectHoldAndResume("truncate epc 2", "backend");
  ExpectHoldAndResume("powercycle 0.5", "backend");
}

TEST_F(BenchInstrumentsTest, AfterAPowerCycleTheDeviceIsSetToTheHeldPhiBeforeAnyoneDrivesIt) {
  const json ports = StartEmulator();
  StartBench(160, BenchScenario(Tcp(ports["epc_tcp"]), Tcp(ports["polarimeter_tcp"])));
  ASSERT_TRUE(Locked()) << Logs();
  controller_->Signal(SIGTERM);  // nobody drives: what the device holds is the driver's doing
  ASSERT_TRUE(Eventually([&] {
    const auto state = LatestState();
    return state && state->mode() == msg::DRIVER_HOLDING;
  }, 5s)) << Logs();
  std::this_thread::sleep_for(300ms);
  const std::vector<double> held = LatestPhi();
  ASSERT_EQ(Control("powercycle 0.5").rfind("OK", 0), 0u);
  // The EPC forgot (0 V); the driver reconnects and sets the held φ again.
  bool restored = false;
  ASSERT_TRUE(Eventually([&] {
    const json status = Status();
    if (status.is_discarded() || status["channels"].size() != held.size()) return false;
    restored = true;
    for (size_t i = 0; i < held.size(); ++i) {
      restored = restored && std::abs(status["channels"][i]["set_v"].get<double>() - held[i]) < 1.5e-4;
    }
    return restored;
  }, 10s)) << Control("status") << "\n" << Logs();
  EXPECT_EQ(LatestPhi(), held);
}

TEST_F(BenchInstrumentsTest, APolarimeterThatFailsGivesNoSamplesThenTheBenchResumes) {
  const json ports = StartEmulator();
  StartBench(153, BenchScenario(Tcp(ports["epc_tcp"]), Tcp(ports["polarimeter_tcp"])));
  ASSERT_TRUE(Locked()) << Logs();
  ASSERT_EQ(Control("garbage polarimeter 20").rfind("OK", 0), 0u);
  ASSERT_EQ(Control("disconnect polarimeter 1").rfind("OK", 0), 0u);
  std::this_thread::sleep_for(1500ms);
  EXPECT_TRUE(Locked(15s)) << Logs();
  EXPECT_NE(Slurp(dir_ + "/polarimeter.log").find("no reading"), std::string::npos) << Logs();
}

}  // namespace
}  // namespace dpc::testing
