// The line-protocol waveplate backend against a scripted device on 127.0.0.1 (FakeDevice), and
// the driver core holding on its faults.

#include "line_waveplates.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "driver_core.h"
#include "driver_core_support.h"
#include "dpc/config/scenario_builders.h"
#include "support/line_server.h"

namespace dpc::services {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

/// An EPC speaking ":SOUR<n>:VOLT <v>" / "OK", ":SOUR<n>:VOLT?", "*IDN?"; it can answer
/// garbage, stop answering, forget its voltages, hang up.
class FakeDevice {
 public:
  enum class Mode { kNormal, kGarbage, kSilent };

  FakeDevice() : server_([this](const std::string& line) { return Reply(line); }) {}
  int port() const { return server_.port(); }
  void set_mode(Mode mode) { mode_ = mode; }
  void HangUp() { server_.HangUp(); }
  /// Forgets every voltage, as after a power cycle.
  void Forget() {
    std::lock_guard<std::mutex> lock(mutex_);
    volts_.clear();
  }
  double volts(int channel) {
    std::lock_guard<std::mutex> lock(mutex_);
    return volts_.count(channel) ? volts_[channel] : 0.0;
  }
  void set_volts(int channel, double v) {
    std::lock_guard<std::mutex> lock(mutex_);
    volts_[channel] = v;
  }
  int sets() const { return sets_; }
  int connections() const { return server_.connections(); }

 private:
  std::optional<std::string> Reply(const std::string& line) {
    const std::string answer = Answer(line);
    switch (mode_.load()) {
      case Mode::kSilent: return std::nullopt;
      case Mode::kGarbage: return std::string("#~?!\n");
      case Mode::kNormal: break;
    }
    return answer + "\n";
  }
  std::string Answer(const std::string& line) {
    int channel = 0;
    char text[64];
    if (line == "*IDN?") return "fake,EPC,3,0";
    if (std::sscanf(line.c_str(), ":SOUR%d:VOLT %63s", &channel, text) == 2 && std::string(text) != "?") {
      std::lock_guard<std::mutex> lock(mutex_);
      volts_[channel] = std::atof(text);
      ++sets_;
      return "OK";
    }
    if (std::sscanf(line.c_str(), ":SOUR%d:VOLT?", &channel) == 1) {
      std::lock_guard<std::mutex> lock(mutex_);
      char out[32];
      std::snprintf(out, sizeof out, "%.6f", volts_.count(channel) ? volts_[channel] : 0.0);
      return out;
    }
    return "ERR unknown command";
  }

  std::atomic<Mode> mode_{Mode::kNormal};
  std::atomic<int> sets_{0};
  std::mutex mutex_;
  std::map<int, double> volts_;
  dpc::testing::LineServer server_;  ///< last: its thread stops before the state above goes
};

WaveplateDeviceConfig Device(int port) {
  WaveplateDeviceConfig d;
  d.link.kind = InstrumentLinkConfig::Kind::kTcp;
  d.link.port = port;
  d.link.response_timeout_s = 0.5;  // generous: a loaded test machine must not look like a fault
  d.link.reconnect_min_s = 0.02;
  d.link.reconnect_max_s = 0.1;
  d.dac_bits = 12;  // 20 V / 4095: 4.9 mV steps
  return d;
}

std::vector<ControlRange> Ranges() { return std::vector<ControlRange>(3, ControlRange{-8.0, 8.0}); }

bool Eventually(const std::function<bool()>& done, std::chrono::milliseconds timeout = 3s) {
  const auto until = Clock::now() + timeout;
  while (Clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(2ms);
  }
  return done();
}

WaveplateMotion Point(std::vector<double> v) { return WaveplateMotion::Still(testing::Controls(v)); }

TEST(LineWaveplatesTest, StartsWhereTheChannelsReadBackAndSetsQuantizedVoltages) {
  FakeDevice device;
  device.set_volts(1, 1.0);
  device.set_volts(2, -2.0);
  device.set_volts(3, 9.5);  // outside the range: clamped to 8 V
  std::vector<std::string> log;
  LineWaveplates waveplates(Device(device.port()), ControlVector::Zero(3), Ranges(),
                            [&](bool, const std::string& text) { log.push_back(text); });
  EXPECT_TRUE(waveplates.started_from_read_back());
  EXPECT_EQ(waveplates.fault(), "");
  EXPECT_FALSE(waveplates.ramps());
  const double lsb = 20.0 / 4095;
  EXPECT_NEAR(waveplates.Applied().phi[0], 1.0, lsb);
  EXPECT_NEAR(waveplates.Applied().phi[2], 8.0, lsb);
  EXPECT_TRUE(Eventually([&] { return std::abs(device.volts(3) - waveplates.Applied().phi[2]) < 1e-4; }));
  EXPECT_EQ(waveplates.limits().max_abs_phi, 10.0);

  ASSERT_EQ(waveplates.Apply(Point({0.1234567, -0.5, 3.0})), "");
  // What the state reports is the DAC's voltage, which the device gets.
  const double set = waveplates.Applied().phi[0];
  EXPECT_NEAR(set, 0.1234567, lsb / 2);
  EXPECT_NE(set, 0.1234567);
  // (The set line carries 4 decimals: {volts:.4f}.)
  EXPECT_TRUE(Eventually([&] {
    return std::abs(device.volts(1) - set) < 1e-4 && std::abs(device.volts(3) - waveplates.Applied().phi[2]) < 1e-4;
  }));
  // Outside the full scale nothing reaches the wire.
  const int sets = device.sets();
  EXPECT_NE(waveplates.Apply(Point({0.0, 12.0, 0.0})).find("outside the device's full scale"), std::string::npos);
  EXPECT_NE(waveplates.Apply(Point({NAN, 0.0, 0.0})), "");
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(device.sets(), sets);
  EXPECT_FALSE(log.empty());
}

TEST(LineWaveplatesTest, AHangUpIsAFaultUntilTheHeldPhiIsSetAgainOnReconnecting) {
  FakeDevice device;
  LineWaveplates waveplates(Device(device.port()), ControlVector::Zero(3), Ranges(), nullptr);
  ASSERT_EQ(waveplates.Apply(Point({1.0, 2.0, 3.0})), "");
  ASSERT_TRUE(Eventually([&] { return std::abs(device.volts(3) - waveplates.Applied().phi[2]) < 1e-4; }));
  const double held = waveplates.Applied().phi[1];
  // The device loses power: it forgets, and the link drops. Nobody commands meanwhile: the
  // backend notices by itself (its idle read-back), reconnects and sets the held φ again.
  device.Forget();
  device.HangUp();
  ASSERT_TRUE(Eventually([&] { return waveplates.fault().empty() && device.connections() >= 2; })) << waveplates.fault();
  EXPECT_NEAR(device.volts(2), held, 1e-4);
  EXPECT_NEAR(device.volts(3), waveplates.Applied().phi[2], 1e-4);
  EXPECT_GE(waveplates.counters().connects, 2u);
}

TEST(LineWaveplatesTest, GarbageOrSilenceIsAFaultThatSaysWhy) {
  FakeDevice device;
  LineWaveplates waveplates(Device(device.port()), ControlVector::Zero(3), Ranges(), nullptr);
  device.set_mode(FakeDevice::Mode::kGarbage);
  ASSERT_EQ(waveplates.Apply(Point({1.0, 0.0, 0.0})), "");
  ASSERT_TRUE(Eventually([&] { return !waveplates.fault().empty(); }));
  EXPECT_NE(waveplates.fault().find("not \"OK\""), std::string::npos) << waveplates.fault();
  EXPECT_GE(waveplates.counters().refused_replies, 1u);
  EXPECT_NE(waveplates.Apply(Point({2.0, 0.0, 0.0})), "");  // refused while in fault

  device.set_mode(FakeDevice::Mode::kSilent);
  ASSERT_TRUE(Eventually([&] { return waveplates.fault().find("no reply") != std::string::npos; }))
      << waveplates.fault();
  EXPECT_GE(waveplates.counters().timeouts, 1u);
  // Answering again: the fault clears, the held φ (1 V on channel 1) is set.
  device.set_mode(FakeDevice::Mode::kNormal);
  ASSERT_TRUE(Eventually([&] { return waveplates.fault().empty(); })) << waveplates.fault();
  EXPECT_NEAR(device.volts(1), waveplates.Applied().phi[0], 1e-4);
  EXPECT_NEAR(waveplates.Applied().phi[0], 1.0, 0.01);
}

TEST(LineWaveplatesTest, AnIdleDeviceThatForgotItsVoltagesIsNoticedAndSetAgain) {
  FakeDevice device;
  LineWaveplates waveplates(Device(device.port()), ControlVector::Zero(3), Ranges(), nullptr);
  ASSERT_EQ(waveplates.Apply(Point({0.5, 0.6, 0.7})), "");
  ASSERT_TRUE(Eventually([&] { return std::abs(device.volts(3) - waveplates.Applied().phi[2]) < 1e-4; }));
  device.Forget();  // the link stays open, as a serial line does through a device's power cycle
  ASSERT_TRUE(Eventually([&] { return std::abs(device.volts(3) - waveplates.Applied().phi[2]) < 1e-4; }, 5s));
  EXPECT_GE(waveplates.counters().connects, 2u);
}

TEST(LineWaveplatesTest, ADeviceThatSettlesIsNotSetAgainBeforeAndGetsTheNewestCommand) {
  FakeDevice device;
  WaveplateDeviceConfig config = Device(device.port());
  config.settling_s = 0.3;
  LineWaveplates waveplates(config, ControlVector::Zero(3), Ranges(), nullptr);
  const int before = device.sets();
  for (int k = 1; k <= 20; ++k) {
    ASSERT_EQ(waveplates.Apply(Point({0.1 * k, 0.0, 0.0})), "");
    std::this_thread::sleep_for(10ms);
  }
  // 20 commands in ~0.2 s: the first set, then (after 0.3 s) only the newest.
  ASSERT_TRUE(Eventually([&] { return std::abs(device.volts(1) - waveplates.Applied().phi[0]) < 1e-4; }));
  EXPECT_LE(device.sets() - before, 3);
  EXPECT_NEAR(device.volts(1), 2.0, 0.01);
}

TEST(LineWaveplatesTest, NoDeviceAtStartIsAFaultFromTheScenariosPhiOn) {
  int port = 0;
  { FakeDevice gone; port = gone.port(); }
  LineWaveplates waveplates(Device(port), testing::Controls({0.25, 0.0, 0.0}), Ranges(), nullptr, 0.2);
  EXPECT_NE(waveplates.fault().find("cannot connect"), std::string::npos) << waveplates.fault();
  EXPECT_NEAR(waveplates.Applied().phi[0], 0.25, 0.01);
  EXPECT_NE(waveplates.Apply(Point({1.0, 0.0, 0.0})), "");
}

TEST(LineWaveplatesTest, TheDriverHoldsWhileTheDeviceIsInFaultAndSaysWhy) {
  FakeDevice device;
  LineWaveplates waveplates(Device(device.port()), ControlVector::Zero(3), Ranges(), nullptr);
  DriverSettings settings;
  settings.max_ramp_s = 0.0;
  std::vector<StageConfig> stages = StagesFromAxes("131");
  for (StageConfig& s : stages) s.range = ControlRange{-8.0, 8.0};
  DriverCore core(stages, settings, &waveplates);
  int64_t now = 10 * testing::kMs;
  auto state = testing::Send(core, testing::Command("A", 0, {0.1, 0.2, 0.3}, 1), now, now);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kActive) << state->reason;
  device.set_mode(FakeDevice::Mode::kSilent);
  ASSERT_TRUE(testing::Send(core, testing::Command("A", 0, {0.2, 0.2, 0.3}, 2), now + testing::kMs, now).has_value());
  ASSERT_TRUE(Eventually([&] { return !waveplates.fault().empty(); }));
  state = core.Tick(now + 2 * testing::kMs, now);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_NE(state->reason.find("no reply"), std::string::npos) << state->reason;
}

}  // namespace
}  // namespace dpc::services
