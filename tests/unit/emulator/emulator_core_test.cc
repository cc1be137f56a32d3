// EmulatorCore and EmulatedDevice: dpc-emulator's instruments and their protocol, driven as the
// program drives them (bytes in, the monotonic time, bytes out), without sockets.
#include "emulator_core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_error.h"
#include "dpc/optics/rotation.h"

namespace dpc::services {
namespace {

constexpr int64_t kStartNs = 1'000'000'000;  // an arbitrary monotonic time
constexpr int64_t kMs = 1'000'000;
constexpr double kPrinted = 2e-6;  // the replies' %.6f

/// θ(V) = c1·V + c3·V³ per channel, as deploy/scenarios/emulator_epc.pbtxt's first channel.
constexpr double kC1 = 0.62, kC3 = 3e-4;
double Theta(double volts) { return kC1 * volts + kC3 * volts * volts * volts; }

/// A 3-stage R1R3R1 EPC in volts (cubic maps, ±10 V) with a still input at S1, valid for dpc sim
/// at 10 kHz.
ScenarioConfig EpcScenario() {
  ScenarioConfig scenario = PaperScenario("131");
  for (StageConfig& stage : scenario.stages) {
    stage.map.kind = ControlMapConfig::Kind::kPolynomial;
    stage.map.coefficients_rad = {0.0, kC1, 0.0, kC3};
    stage.range = ControlRange{-10.0, 10.0};
  }
  scenario.input.initial_sop = StokesVector(1.0, 0.0, 0.0);
  scenario.input.disturbances.clear();
  scenario.simulation.sample_rate_hz = 10e3;
  scenario.simulation.delay_s = 1e-4;
  scenario.simulation.duration_s = 1.0;
  scenario.controller.dither.reset_duration_s = 1e-4;
  return scenario;
}

/// One fixed-axis stage about S1 (the EPC's channel 1) with the input at S2: S_out turns by θ in
/// the S2–S3 plane, (0, cos θ, sin θ).
ScenarioConfig OneStageScenario() {
  ScenarioConfig scenario = EpcScenario();
  scenario.stages.resize(1);
  scenario.input.initial_sop = StokesVector(0.0, 1.0, 0.0);
  return scenario;
}

std::vector<double> Numbers(const std::string& reply) {
  std::vector<double> values;
  std::stringstream in(reply);
  std::string field;
  while (std::getline(in, field, ',')) values.push_back(std::stod(field));
  return values;
}

StokesVector Sop(const std::string& reply) {
  const std::vector<double> v = Numbers(reply);
  EXPECT_EQ(v.size(), 3u) << reply;
  return v.size() == 3 ? StokesVector(v[0], v[1], v[2]) : StokesVector::Zero();
}

/// An emulator and one client per instrument, at a time the test moves.
class EmulatorCoreTest : public ::testing::Test {
 protected:
  void Start(const ScenarioConfig& scenario = EpcScenario(), const EmulatorSettings& settings = {}) {
    now_ns_ = kStartNs;
    core_.emplace(scenario, settings, now_ns_,
                  [this](const std::string& kind, const std::string& text) { events_.push_back(kind + ": " + text); });
    epc_ = *core_->Open(Instrument::kEpc, now_ns_);
    polarimeter_ = *core_->Open(Instrument::kPolarimeter, now_ns_);
    control_ = *core_->Open(Instrument::kControl, now_ns_);
  }
  void Send(EmulatorCore::SessionId id, const std::string& bytes) { core_->Receive(id, bytes, now_ns_); }
  /// Everything due to the session by now, taken.
  std::string Take(EmulatorCore::SessionId id) {
    std::string out(core_->Output(id, now_ns_));
    core_->Written(id, out.size());
    return out;
  }
  /// The reply to one line, without its newline ("" if none is due yet).
  std::string Ask(EmulatorCore::SessionId id, const std::string& line) {
    Send(id, line + "\n");
    std::string reply = Take(id);
    if (!reply.empty() && reply.back() == '\n') reply.pop_back();
    return reply;
  }
  void Wait(int64_t ns) {
    now_ns_ += ns;
    core_->Advance(now_ns_);
  }
  nlohmann::json Status() { return nlohmann::json::parse(Ask(control_, "status")); }

  std::optional<EmulatorCore> core_;
  int64_t now_ns_ = kStartNs;
  EmulatorCore::SessionId epc_ = 0, polarimeter_ = 0, control_ = 0;
  std::vector<std::string> events_;
};

// ---- settings and the DAC ----------------------------------------------------------------------

TEST(EmulatorSettingsTest, EachBadSettingIsRefusedNamingItsOption) {
  const auto problem = [](auto change) {
    EmulatorSettings settings;
    change(settings);
    try {
      ValidateEmulatorSettings(settings);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(problem([](EmulatorSettings&) {}), "");
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.dac_bits = 0; }).rfind("--dac-bits: 0", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.dac_bits = 33; }).rfind("--dac-bits: 33", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.volts_max = -10; }).rfind("--volts-max", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.volts_min = NAN; }).rfind("--volts-min", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.settling_s = -1; }).rfind("--settling-s", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.hysteresis_v = 10.5; }).rfind("--hysteresis-v", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.latency_s = -0.1; }).rfind("--latency-s", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.temperature_c = 500; }).rfind("--temperature-c", 0), 0u);
  EXPECT_EQ(problem([](EmulatorSettings& s) { s.temperature_coefficient_per_k = 1; })
                .rfind("--temperature-coefficient-per-k", 0),
            0u);
  // 1 + k·(T − 25) must stay positive: −0.05/K at 45 °C would leave no retardance.
  const std::string vanished = problem([](EmulatorSettings& s) {
    s.temperature_coefficient_per_k = -0.05;
    s.temperature_c = 45;
  });
  EXPECT_NE(vanished.find("--temperature-c: at 45 °C the retardance factor"), std::string::npos) << vanished;
}

TEST(DacScaleTest, QuantizesToTheNearestOfItsCodesBothEndsIncluded) {
  const DacScale dac(3, -10.0, 10.0);  // 8 codes, 20/7 V apart
  EXPECT_DOUBLE_EQ(dac.step_v(), 20.0 / 7.0);
  EXPECT_EQ(dac.Quantize(-10.0), -10.0);
  EXPECT_EQ(dac.Quantize(10.0), 10.0);
  EXPECT_DOUBLE_EQ(dac.Quantize(0.0), -10.0 + 4 * 20.0 / 7.0);  // 1.428…: the nearest code to 0
  EXPECT_EQ(dac.Quantize(-8.6), -10.0);  // 0.49 of a step above the bottom code
  EXPECT_DOUBLE_EQ(dac.Quantize(-8.5), -10.0 + 20.0 / 7.0);
  const DacScale sixteen(16, -10.0, 10.0);
  EXPECT_NEAR(sixteen.Quantize(1.23456), 1.23456, sixteen.step_v() / 2);
  EXPECT_NE(sixteen.Quantize(1.23456), 1.23456);
}

TEST(EpcChannelTest, ThePlayOperatorMovesOnlyWhenTheSetVoltagePullsBeyondItsHalfWidth) {
  EpcChannel channel(0.5, 0.0);
  channel.Set(2.0);
  EXPECT_DOUBLE_EQ(channel.effective_v(), 1.5);
  channel.Set(1.8);  // back within the play: nothing moves
  EXPECT_DOUBLE_EQ(channel.effective_v(), 1.5);
  channel.Set(1.0);
  EXPECT_DOUBLE_EQ(channel.effective_v(), 1.5);
  channel.Set(0.8);  // pulled down past the other side
  EXPECT_DOUBLE_EQ(channel.effective_v(), 1.3);
  channel.Set(3.0);
  EXPECT_DOUBLE_EQ(channel.effective_v(), 2.5);
  EXPECT_DOUBLE_EQ(channel.set_v(), 3.0);
  channel.Reset();
  EXPECT_EQ(channel.effective_v(), 0.0);
}

TEST(EpcChannelTest, SettlesExponentiallyWithItsTimeConstantWhateverTheSteps) {
  EpcChannel one_step(0.0, 0.1), many_steps(0.0, 0.1);
  one_step.Set(5.0);
  many_steps.Set(5.0);
  EXPECT_EQ(one_step.effective_v(), 0.0);
  one_step.Advance(0.1);
  for (int i = 0; i < 100; ++i) many_steps.Advance(0.001);
  EXPECT_NEAR(one_step.effective_v(), 5.0 * (1.0 - std::exp(-1.0)), 1e-12);
  EXPECT_NEAR(many_steps.effective_v(), one_step.effective_v(), 1e-12);
}

TEST(ScaleRetardancesTest, ScalesEveryMapAndFixedRetardanceButNoOrientation) {
  std::vector<StageConfig> stages = StagesFromAxes("13");
  stages[1].map.kind = ControlMapConfig::Kind::kTable;
  stages[1].map.table_control = {0, 1};
  stages[1].map.table_angle_rad = {0.5, 2.0};
  StageConfig adjustable;
  adjustable.kind = StageConfig::Kind::kAdjustableAxis;
  adjustable.retardance.fixed_rad = M_PI / 2;
  adjustable.orientation.controlled = true;
  adjustable.orientation.map.rad_per_unit = 1.0;
  stages.push_back(adjustable);
  const std::vector<StageConfig> hot = ScaleRetardances(stages, 1.1);
  EXPECT_DOUBLE_EQ(hot[0].map.rad_per_unit, M_PI * 1.1);
  EXPECT_DOUBLE_EQ(hot[1].map.table_angle_rad[1], 2.2);
  EXPECT_DOUBLE_EQ(hot[2].retardance.fixed_rad, M_PI / 2 * 1.1);
  EXPECT_DOUBLE_EQ(hot[2].orientation.map.rad_per_unit, 1.0);
}

TEST(EmulatedDeviceTest, RefusesAnInvalidScenarioOrAnInputTooFastToStepInRealTime) {
  ScenarioConfig bad = EpcScenario();
  bad.stages[1].map.coefficients_rad = {1.0, 0.0};  // constant: no control
  EXPECT_THROW(EmulatedDevice(bad, {}, kStartNs), ScenarioError);
  ScenarioConfig fast = EpcScenario();
  fast.simulation.sample_rate_hz = 50e6;
  fast.simulation.delay_s = 1e-6;
  fast.controller.dither.reset_duration_s = 1e-6;
  try {
    EmulatedDevice device(fast, {}, kStartNs);
    FAIL() << "a 50-MHz input was taken";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location(), "simulation.sample_rate_hz");
  }
  EmulatorSettings settings;
  settings.dac_bits = 0;
  EXPECT_THROW(EmulatedDevice(EpcScenario(), settings, kStartNs), std::invalid_argument);
}

TEST(EmulatedDeviceTest, TheInputAdvancesWithTheWallClockAndSkipsAStallBeyondItsCatchUp) {
  ScenarioConfig scenario = EpcScenario();
  DisturbanceConfig rotation;
  rotation.kind = DisturbanceConfig::Kind::kConstantRotation;
  rotation.rate_rad_per_s = 10.0;
  rotation.axis = Vector3::UnitZ();
  scenario.input.disturbances = {rotation};
  scenario.simulation.sample_rate_hz = 1e3;
  scenario.simulation.delay_s = 1e-3;
  scenario.controller.dither.reset_duration_s = 1e-3;
  EmulatedDevice device(scenario, {}, kStartNs);
  EXPECT_NEAR(SphereAngleRad(device.s_in(), StokesVector::UnitX()), 0.0, 1e-12);
  device.Advance(kStartNs + 100 * kMs + kMs / 2);  // 100.5 periods: 100 steps of 10 mrad
  EXPECT_EQ(device.input_steps(), 100);
  EXPECT_NEAR(SphereAngleRad(device.s_in(), StokesVector::UnitX()), 1.0, 1e-9);
  device.Advance(kStartNs + 50 * kMs);  // the past changes nothing
  EXPECT_EQ(device.input_steps(), 100);
  // A stall of 10 s: one second is caught up, the other 9 s skipped (and counted).
  device.Advance(kStartNs + 10'100 * kMs);
  EXPECT_EQ(device.input_steps(), 1100);
  EXPECT_EQ(device.input_steps_skipped(), 9000);
  device.Advance(kStartNs + 10'101 * kMs);
  EXPECT_EQ(device.input_steps(), 1101);
}

// ---- the EPC -----------------------------------------------------------------------------------

TEST_F(EmulatorCoreTest, EpcIdentifiesItselfWithItsChannelCount) {
  Start();
  EXPECT_EQ(Ask(epc_, "*IDN?"), "dpc-emulator,EPC,3,0.1");
  EXPECT_EQ(Ask(epc_, "*idn?"), "dpc-emulator,EPC,3,0.1");
}

TEST_F(EmulatorCoreTest, EpcSetsTheQuantizedVoltageAndReportsIt) {
  EmulatorSettings settings;
  settings.dac_bits = 8;  // 255 steps of 78.4 mV over ±10 V
  Start(EpcScenario(), settings);
  EXPECT_EQ(Ask(epc_, ":SOUR2:VOLT 1.3"), "OK");
  const double expected = DacScale(8, -10, 10).Quantize(1.3);
  EXPECT_NE(expected, 1.3);
  EXPECT_EQ(Ask(epc_, ":SOUR2:VOLT?"), fmt::format("{:.6f}", expected));
  EXPECT_EQ(core_->device().set_v(1), expected);
  EXPECT_EQ(core_->device().effective_v(1), expected);
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT?"), "0.000000");
  // Case, a '+', an exponent, "\r\n" and blanks around are all taken.
  EXPECT_EQ(Ask(epc_, "  :sour3:volt +2.5e0\r"), "OK");
  EXPECT_EQ(Ask(epc_, ":SOUR3:VOLT -10"), "OK");
  EXPECT_EQ(Ask(epc_, ":SOUR3:VOLT?"), "-10.000000");
  EXPECT_EQ(Ask(epc_, ":SOUR3:VOLT 10"), "OK");
  EXPECT_EQ(Ask(epc_, ":SOUR3:VOLT?"), "10.000000");
}

TEST_F(EmulatorCoreTest, EpcRefusesWhatItCannotSetAndChangesNothing) {
  Start();
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 2"), "OK");
  const double before = core_->device().set_v(0);
  for (const char* line : {":SOUR1:VOLT 10.001", ":SOUR1:VOLT -11", ":SOUR1:VOLT nan", ":SOUR1:VOLT inf",
                           ":SOUR1:VOLT 1e400", ":SOUR1:VOLT abc", ":SOUR1:VOLT 1.5V", ":SOUR1:VOLT 0x10",
                           ":SOUR1:VOLT"}) {
    const std::string reply = Ask(epc_, line);
    EXPECT_EQ(reply.rfind("ERR ", 0), 0u) << line << " → " << reply;
  }
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT 10.001"), "ERR 10.001 V is outside the full scale [-10, 10] V");
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT nan"), "ERR voltage not finite");
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT abc"), "ERR voltage is not a decimal number");
  EXPECT_EQ(Ask(epc_, ":SOUR4:VOLT 1"), "ERR unknown channel 4 (channels 1-3)");
  EXPECT_EQ(Ask(epc_, ":SOUR0:VOLT?"), "ERR unknown channel 0 (channels 1-3)");
  EXPECT_EQ(Ask(epc_, ":SOUR99999999999999:VOLT?"), "ERR unknown channel (channels 1-3)");
  EXPECT_EQ(core_->device().set_v(0), before);
  for (const char* line : {"*RST", ":SOUR:VOLT 1", ":SOUR1:CURR 1", ":SOUR1:VOLTAGE 1", ":MEAS:SOP?", "VOLT 1"}) {
    EXPECT_EQ(Ask(epc_, line), "ERR unknown command") << line;
  }
  EXPECT_EQ(Ask(epc_, ""), "");  // a blank line asks nothing
  EXPECT_EQ(Ask(epc_, " \r"), "");
  const nlohmann::json status = Status();
  EXPECT_EQ(status["epc"]["sets"], 1);
  EXPECT_EQ(status["epc"]["errors"], 21);
}

TEST_F(EmulatorCoreTest, AChannelsRangeInTheScenarioNarrowsTheFullScale) {
  ScenarioConfig scenario = EpcScenario();
  scenario.stages[1].range = ControlRange{-5.0, 5.0};
  Start(scenario);
  EXPECT_EQ(Ask(epc_, ":SOUR2:VOLT 6"), "ERR 6 V is outside channel 2's range [-5, 5] V");
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT 6"), "OK");
}

// ---- the polarimeter and the optics ------------------------------------------------------------

TEST_F(EmulatorCoreTest, PolarimeterMeasuresTheOutputThroughTheNonlinearMapsOfTheVolts) {
  Start(OneStageScenario());
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");
  EXPECT_EQ(Ask(polarimeter_, ":MEAS:SOP?"), "0.000000,1.000000,0.000000");
  for (double volts : {1.0, 5.0, -7.5, 10.0}) {
    ASSERT_EQ(Ask(epc_, fmt::format(":SOUR1:VOLT {}", volts)), "OK");
    const double v = core_->device().effective_v(0);
    const double theta = Theta(v);  // not π·V, not 0.62·V: the cubic term counts
    const StokesVector s_out = Sop(Ask(polarimeter_, ":MEAS:SOP?"));
    EXPECT_NEAR(s_out.x(), 0.0, kPrinted) << volts;
    EXPECT_NEAR(s_out.y(), std::cos(theta), kPrinted) << volts;
    EXPECT_NEAR(s_out.z(), std::sin(theta), kPrinted) << volts;
  }
  EXPECT_EQ(Ask(polarimeter_, ":MEAS:SIN?"), "0.000000,1.000000,0.000000");
  const std::vector<double> both = Numbers(Ask(polarimeter_, ":meas:both?"));
  ASSERT_EQ(both.size(), 6u);
  EXPECT_NEAR(both[1], 1.0, kPrinted);
  EXPECT_NEAR(both[4], std::cos(Theta(10.0)), kPrinted);
  EXPECT_EQ(Ask(polarimeter_, ":MEAS:POW?"), "ERR unknown command");
  EXPECT_EQ(Ask(polarimeter_, ":SOUR1:VOLT 1"), "ERR unknown command");
}

TEST_F(EmulatorCoreTest, ThreeStagesGiveTheChainOfTheScenario) {
  Start();
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 3"), "OK");
  ASSERT_EQ(Ask(epc_, ":SOUR2:VOLT -4"), "OK");
  ASSERT_EQ(Ask(epc_, ":SOUR3:VOLT 6.5"), "OK");
  ControlVector volts(3);
  for (int c = 0; c < 3; ++c) volts[c] = core_->device().set_v(c);
  // R1(θ3)·R3(θ2)·R1(θ1)·S_in, written out.
  const StokesVector expected = R1(Theta(volts[2])) * R3(Theta(volts[1])) * R1(Theta(volts[0])) * StokesVector::UnitX();
  const StokesVector measured = Sop(Ask(polarimeter_, ":MEAS:SOP?"));
  EXPECT_LT((measured - expected).norm(), 2 * kPrinted) << measured.transpose() << " vs " << expected.transpose();
}

TEST_F(EmulatorCoreTest, TheOutputFollowsTheSettlingEffectiveVoltageNotTheSetOne) {
  EmulatorSettings settings;
  settings.settling_s = 0.1;
  Start(OneStageScenario(), settings);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 5"), "OK");
  const double set = core_->device().set_v(0);
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT?"), fmt::format("{:.6f}", set));  // the set voltage at once
  EXPECT_EQ(core_->device().effective_v(0), 0.0);
  EXPECT_EQ(Ask(polarimeter_, ":MEAS:SOP?"), "0.000000,1.000000,0.000000");
  Wait(100 * kMs);
  const double effective = set * (1.0 - std::exp(-1.0));
  EXPECT_NEAR(core_->device().effective_v(0), effective, 1e-9);
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(Theta(effective)), kPrinted);
  const nlohmann::json status = Status();
  EXPECT_NEAR(status["channels"][0]["effective_v"].get<double>(), effective, 1e-9);
  EXPECT_EQ(status["channels"][0]["set_v"].get<double>(), set);
  Wait(2'000 * kMs);
  EXPECT_NEAR(core_->device().effective_v(0), set, 1e-6);
}

TEST_F(EmulatorCoreTest, HysteresisLeavesTheOutputWhereThePlayHoldsIt) {
  EmulatorSettings settings;
  settings.hysteresis_v = 0.25;
  settings.dac_bits = 20;
  Start(OneStageScenario(), settings);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 4"), "OK");
  const StokesVector up = Sop(Ask(polarimeter_, ":MEAS:SOP?"));
  EXPECT_NEAR(core_->device().effective_v(0), 3.75, 1e-5);  // 4 V on the DAC's nearest code, less the play
  EXPECT_NEAR(core_->device().effective_v(0), core_->device().set_v(0) - 0.25, 1e-12);
  EXPECT_NEAR(up.z(), std::sin(Theta(core_->device().effective_v(0))), kPrinted);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 3.6"), "OK");  // back by less than the play's width
  EXPECT_EQ(Sop(Ask(polarimeter_, ":MEAS:SOP?")), up);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 3"), "OK");
  EXPECT_NEAR(core_->device().effective_v(0), 3.25, 1e-5);
}

TEST_F(EmulatorCoreTest, TemperatureScalesEveryRetardanceAndMovesTheOutput) {
  EmulatorSettings settings;
  settings.temperature_c = 35.0;  // k = 2e-3/K: θ·1.02
  Start(OneStageScenario(), settings);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 5"), "OK");
  const double v = core_->device().set_v(0);
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(1.02 * Theta(v)), kPrinted);
  EXPECT_EQ(Ask(control_, "temperature 25"), "OK temperature 25 C");
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(Theta(v)), kPrinted);
  EXPECT_EQ(Ask(control_, "temperature -5.5"), "OK temperature -5.5 C");
  const StokesVector cold = Sop(Ask(polarimeter_, ":MEAS:SOP?"));
  EXPECT_NEAR(cold.z(), std::sin(0.939 * Theta(v)), kPrinted);
  // The drift is what the controller must follow: at 5 V, 30 K move S_out by 0.06·θ ≈ 10°.
  EXPECT_GT(SphereAngleRad(cold, StokesVector(0, std::cos(Theta(v)), std::sin(Theta(v)))), 0.15);
  EXPECT_EQ(Ask(control_, "temperature 900").rfind("ERR temperature: 900 °C is not in", 0), 0u);
  EXPECT_EQ(Ask(control_, "temperature warm"), "ERR temperature must be a finite number");
  EXPECT_EQ(core_->device().temperature_c(), -5.5);
  EXPECT_EQ(Status()["temperature_c"], -5.5);
}

TEST_F(EmulatorCoreTest, WavelengthScalesEveryRetardanceAsOneOverLambda) {
  EmulatorSettings settings;
  settings.wavelength_nm = 1500.0;  // θ·1550/1500
  Start(OneStageScenario(), settings);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 5"), "OK");
  const double v = core_->device().set_v(0);
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(1550.0 / 1500.0 * Theta(v)), kPrinted);
  EXPECT_EQ(Ask(control_, "wavelength 1550"), "OK wavelength 1550 nm");
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(Theta(v)), kPrinted);
  // With the temperature: the two factors multiply.
  EXPECT_EQ(Ask(control_, "temperature 35"), "OK temperature 35 C");
  EXPECT_EQ(Ask(control_, "wavelength 1600"), "OK wavelength 1600 nm");
  EXPECT_NEAR(Sop(Ask(polarimeter_, ":MEAS:SOP?")).z(), std::sin(1.02 * 1550.0 / 1600.0 * Theta(v)), kPrinted);
  EXPECT_EQ(Ask(control_, "wavelength 9000").rfind("ERR wavelength: 9000 nm is not in", 0), 0u);
  EXPECT_EQ(Ask(control_, "wavelength red"), "ERR wavelength must be a finite number");
  EXPECT_EQ(Ask(control_, "wavelength"), "ERR usage: wavelength <nm>");
  EXPECT_EQ(core_->device().wavelength_nm(), 1600.0);
  EXPECT_EQ(Status()["wavelength_nm"], 1600.0);
  EmulatorSettings bad;
  bad.wavelength_nm = NAN;
  EXPECT_THROW(ValidateEmulatorSettings(bad), std::invalid_argument);
}

TEST_F(EmulatorCoreTest, NoiseDisplacesEachMeasurementByAboutSigma) {
  ScenarioConfig scenario = OneStageScenario();
  scenario.simulation.polarimeter_noise_deg = 1.0;
  Start(scenario);
  double sum_squares = 0.0;
  constexpr int kReadings = 2000;
  for (int i = 0; i < kReadings; ++i) {
    const StokesVector s = Sop(Ask(polarimeter_, ":MEAS:SIN?"));
    EXPECT_NEAR(s.norm(), 1.0, 4 * kPrinted);
    sum_squares += std::pow(SphereAngleRad(s.normalized(), StokesVector::UnitY()), 2);
  }
  // The angular error is Rayleigh with scale σ: RMS σ·√2.
  EXPECT_NEAR(std::sqrt(sum_squares / kReadings), std::sqrt(2.0) * M_PI / 180.0, 0.1 * M_PI / 180.0);
}

// ---- timing and faults ---------------------------------------------------------------------------

TEST_F(EmulatorCoreTest, RepliesLeaveTheirLatencyAfterTheQueryInOrder) {
  EmulatorSettings settings;
  settings.latency_s = 0.01;
  Start(EpcScenario(), settings);
  Send(epc_, "*IDN?\n:SOUR1:VOLT 1\n");
  EXPECT_EQ(Take(epc_), "");
  EXPECT_EQ(core_->NextDueNs(), kStartNs + 10 * kMs);
  Wait(10 * kMs - 1);
  EXPECT_EQ(Take(epc_), "");
  Wait(1);
  EXPECT_EQ(Take(epc_), "dpc-emulator,EPC,3,0.1\nOK\n");
  EXPECT_EQ(core_->NextDueNs(), INT64_MAX);
  // The voltage was applied when the command came, not when its reply left.
  EXPECT_NE(core_->device().set_v(0), 0.0);
  // The control port answers at once.
  EXPECT_EQ(Ask(control_, "help").rfind("OK disconnect", 0), 0u);
}

TEST_F(EmulatorCoreTest, SlowRepliesComeLateAndThoseAfterThemWait) {
  Start();
  EXPECT_EQ(Ask(control_, "slow polarimeter 0.5 1"), "OK slow polarimeter: the next 1 reply 0.5 s late");
  Send(polarimeter_, "*IDN?\n*IDN?\n");
  EXPECT_EQ(Take(polarimeter_), "");
  Wait(499 * kMs);
  EXPECT_EQ(Take(polarimeter_), "");
  Wait(1 * kMs);
  EXPECT_EQ(Take(polarimeter_), "dpc-emulator,POL,0,0.1\ndpc-emulator,POL,0,0.1\n");
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");
  EXPECT_EQ(Ask(epc_, "*IDN?"), "dpc-emulator,EPC,3,0.1");  // the other instrument is not slowed
}

TEST_F(EmulatorCoreTest, GarbageRepliesAreJunkLinesThatParseAsNoReply) {
  Start();
  EXPECT_EQ(Ask(control_, "garbage epc 3"), "OK garbage epc: the next 3 replies");
  const EmulatorCore::SessionId other = *core_->Open(Instrument::kEpc, now_ns_);
  for (EmulatorCore::SessionId id : {epc_, other, epc_}) {  // counted across the instrument's sessions
    const std::string junk = Ask(id, ":SOUR1:VOLT?");
    ASSERT_GE(junk.size(), 8u);
    for (char c : junk) {
      EXPECT_TRUE(c >= 0x21 && c <= 0x7e) << junk;
      EXPECT_EQ(std::string("0123456789+-.,OKERokerdpc").find(c), std::string::npos) << junk;
    }
    EXPECT_EQ(junk.find('\n'), std::string::npos);
  }
  EXPECT_EQ(Ask(epc_, ":SOUR1:VOLT?"), "0.000000");
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");
}

TEST_F(EmulatorCoreTest, TruncatedRepliesAreTheirFirstHalfWithoutANewline) {
  Start(OneStageScenario());
  EXPECT_EQ(Ask(control_, "truncate polarimeter 2"), "OK truncate polarimeter: the next 2 replies");
  EXPECT_EQ(Ask(polarimeter_, ":MEAS:SIN?"), "0.000000,1.00");  // 13 of "0.000000,1.000000,0.000000"
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulato");
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");
  // Both faults at once: garbage first (truncate keeps its count).
  Ask(control_, "truncate epc 1");
  Ask(control_, "garbage epc 1");
  EXPECT_EQ(Take(epc_), "");
  const std::string junk = Ask(epc_, "*IDN?");
  EXPECT_EQ(junk.find("dpc"), std::string::npos) << junk;
  EXPECT_EQ(Ask(epc_, "*IDN?"), "dpc-emulato");
}

TEST_F(EmulatorCoreTest, DisconnectEndsTheInstrumentsSessionsAndRefusesNewOnesForAWhile) {
  Start();
  const EmulatorCore::SessionId second = *core_->Open(Instrument::kEpc, now_ns_);
  EXPECT_EQ(Ask(control_, "disconnect epc 1.5"), "OK disconnect epc: 2 sessions ended, new ones refused for 1.5 s");
  EXPECT_EQ(core_->TakeEnded(), (std::vector<EmulatorCore::SessionId>{epc_, second}));
  EXPECT_FALSE(core_->IsOpen(epc_));
  Send(epc_, "*IDN?\n");  // an ended session takes nothing more
  EXPECT_EQ(core_->Output(epc_, now_ns_), "");
  EXPECT_FALSE(core_->Reachable(Instrument::kEpc, now_ns_));
  EXPECT_FALSE(core_->Open(Instrument::kEpc, now_ns_));
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");  // the other instrument stays
  const nlohmann::json status = Status();
  EXPECT_EQ(status["epc"]["connections"]["open"], 0);
  EXPECT_EQ(status["epc"]["connections"]["ended"], 2);
  EXPECT_EQ(status["epc"]["connections"]["refused"], 1);
  ASSERT_EQ(status["faults"].size(), 1u);
  EXPECT_EQ(status["faults"][0]["fault"], "unreachable");
  EXPECT_EQ(status["faults"][0]["reason"], "disconnect");
  Wait(1'500 * kMs);
  const std::optional<EmulatorCore::SessionId> again = core_->Open(Instrument::kEpc, now_ns_);
  ASSERT_TRUE(again);
  EXPECT_EQ(Ask(*again, "*IDN?"), "dpc-emulator,EPC,3,0.1");
  // "all", default 0 s: the sessions go, new ones are taken at once.
  EXPECT_EQ(Ask(control_, "disconnect all"), "OK disconnect all: 2 sessions ended, new ones refused for 0 s");
  EXPECT_TRUE(core_->Open(Instrument::kPolarimeter, now_ns_));
  EXPECT_TRUE(core_->IsOpen(control_));
  EXPECT_FALSE(events_.empty());
}

TEST_F(EmulatorCoreTest, PowerCycleForgetsEveryVoltageAndTakesTheEpcAway) {
  EmulatorSettings settings;
  settings.settling_s = 0.05;
  Start(EpcScenario(), settings);
  ASSERT_EQ(Ask(epc_, ":SOUR1:VOLT 3"), "OK");
  ASSERT_EQ(Ask(epc_, ":SOUR2:VOLT -2"), "OK");
  Wait(20 * kMs);
  EXPECT_NE(core_->device().effective_v(0), 0.0);
  EXPECT_EQ(Ask(control_, "powercycle"),
            "OK powercycle: every channel at 0 V, 1 session ended, the EPC unreachable for 0.5 s");
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(core_->device().set_v(c), 0.0);
    EXPECT_EQ(core_->device().effective_v(c), 0.0);
  }
  EXPECT_EQ(core_->TakeEnded(), std::vector<EmulatorCore::SessionId>{epc_});
  Wait(499 * kMs);
  EXPECT_FALSE(core_->Open(Instrument::kEpc, now_ns_));
  Wait(1 * kMs);
  const EmulatorCore::SessionId back = *core_->Open(Instrument::kEpc, now_ns_);
  EXPECT_EQ(Ask(back, ":SOUR1:VOLT?"), "0.000000");
  EXPECT_EQ(Ask(control_, "powercycle 0"), "OK powercycle: every channel at 0 V, 1 session ended, the EPC unreachable for 0 s");
  EXPECT_TRUE(core_->Open(Instrument::kEpc, now_ns_));
}

TEST_F(EmulatorCoreTest, ControlPortRefusesBadCommandsWithTheirUsage) {
  Start();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"frobnicate", "ERR unknown command; disconnect epc|polarimeter|all [seconds];"},
      {"disconnect", "ERR usage: disconnect epc|polarimeter|all [seconds]"},
      {"disconnect laser", "ERR usage: disconnect epc|polarimeter|all [seconds]"},
      {"disconnect epc -1", "ERR seconds must be a number in [0, 3600]"},
      {"disconnect epc nan", "ERR seconds must be a number in [0, 3600]"},
      {"garbage all 3", "ERR usage: garbage epc|polarimeter <count>"},
      {"garbage epc 1.5", "ERR count must be a whole number in [0, 1000000000]"},
      {"truncate polarimeter -2", "ERR count must be a whole number in [0, 1000000000]"},
      {"slow epc 1", "ERR usage: slow epc|polarimeter <seconds> <count>"},
      {"slow epc 1e9 1", "ERR seconds must be a number in [0, 3600]"},
      {"powercycle 1 2", "ERR usage: powercycle [seconds]"},
      {"temperature", "ERR usage: temperature <celsius>"},
      {"status now", "ERR unknown command; disconnect epc|polarimeter|all [seconds];"},
  };
  for (const auto& [line, expected] : cases) {
    EXPECT_EQ(Ask(control_, line).rfind(expected, 0), 0u) << line << " → " << Ask(control_, line);
  }
  EXPECT_TRUE(core_->Reachable(Instrument::kEpc, now_ns_));
  EXPECT_EQ(Status()["faults"].size(), 0u);
  EXPECT_EQ(Ask(control_, "GARBAGE EPC 0"), "OK garbage epc: the next 0 replies");
}

TEST_F(EmulatorCoreTest, StatusIsOneJsonLineWithTheDeviceCountersAndFaults) {
  Start(OneStageScenario());
  Ask(epc_, ":SOUR1:VOLT 2");
  Ask(epc_, ":SOUR1:VOLT?");
  Ask(epc_, ":SOUR1:VOLT 20");
  Ask(polarimeter_, ":MEAS:BOTH?");
  Ask(control_, "garbage polarimeter 4");
  Ask(control_, "slow epc 0.25 2");
  Wait(3 * kMs);
  Send(control_, "status\n");
  const std::string line = Take(control_);
  ASSERT_EQ(line.find('\n'), line.size() - 1) << line;
  const nlohmann::json status = nlohmann::json::parse(line);
  EXPECT_NEAR(status["time_s"].get<double>(), 0.003, 1e-9);
  EXPECT_EQ(status["temperature_c"], 25.0);
  ASSERT_EQ(status["channels"].size(), 1u);
  EXPECT_NEAR(status["channels"][0]["set_v"].get<double>(), 2.0, 1e-3);
  EXPECT_EQ(status["s_in"], (std::vector<double>{0.0, 1.0, 0.0}));
  const double theta = Theta(core_->device().effective_v(0));
  EXPECT_NEAR(status["s_out"][2].get<double>(), std::sin(theta), 1e-12);
  EXPECT_EQ(status["epc"]["queries"], 1);
  EXPECT_EQ(status["epc"]["sets"], 1);
  EXPECT_EQ(status["epc"]["errors"], 1);
  EXPECT_EQ(status["epc"]["connections"]["open"], 1);
  EXPECT_EQ(status["epc"]["connections"]["accepted"], 1);
  EXPECT_EQ(status["polarimeter"]["queries"], 1);
  EXPECT_EQ(status["control"]["commands"], 2);  // this status is counted after it is written
  ASSERT_EQ(status["faults"].size(), 2u);
  EXPECT_EQ(status["faults"][0], nlohmann::json({{"instrument", "epc"}, {"fault", "slow"}, {"replies", 2},
                                                 {"seconds", 0.25}}));
  EXPECT_EQ(status["faults"][1], nlohmann::json({{"instrument", "polarimeter"}, {"fault", "garbage"}, {"replies", 4}}));
}

// ---- bounds ----------------------------------------------------------------------------------------

TEST_F(EmulatorCoreTest, ALineLongerThan256BytesIsAnsweredOnceAndDropped) {
  Start();
  // 256 bytes and "\r\n" is a line (an unknown command), not too long.
  EXPECT_EQ(Ask(epc_, std::string(256, 'A') + "\r"), "ERR unknown command");
  EXPECT_EQ(Ask(epc_, std::string(257, 'A')), "ERR line too long");
  // 300 bytes then a command on the next line: one error for the long line, then the answer.
  Send(epc_, std::string(300, 'B'));
  EXPECT_EQ(Take(epc_), "ERR line too long\n");
  Send(epc_, std::string(5000, 'C'));
  EXPECT_EQ(Take(epc_), "");  // still the same line: dropped
  Send(epc_, "\n*IDN?\n");
  EXPECT_EQ(Take(epc_), "dpc-emulator,EPC,3,0.1\n");
  EXPECT_EQ(Ask(control_, std::string(400, 'x')), "ERR line too long");
}

TEST_F(EmulatorCoreTest, AClientThatDoesNotReadIsEndedOnce64KiBAreQueued) {
  EmulatorSettings settings;
  settings.latency_s = 1.0;  // nothing leaves: every reply stays queued
  Start(EpcScenario(), settings);
  const std::string query = "*IDN?\n";  // 23 bytes of reply each
  int sent = 0;
  while (core_->IsOpen(epc_) && sent < 10'000) {
    Send(epc_, query);
    ++sent;
  }
  EXPECT_FALSE(core_->IsOpen(epc_));
  EXPECT_EQ(sent, static_cast<int>(EmulatorCore::kMaxQueuedBytes / 23) + 1);
  EXPECT_EQ(core_->TakeEnded(), std::vector<EmulatorCore::SessionId>{epc_});
  ASSERT_FALSE(events_.empty());
  EXPECT_NE(events_.back().find("does not read its replies"), std::string::npos) << events_.back();
  // Written-but-unread bytes count as well: a client that reads nothing, latency 0.
  Start();
  for (int i = 0; i < 10'000 && core_->IsOpen(polarimeter_); ++i) Send(polarimeter_, ":MEAS:SOP?\n");
  EXPECT_FALSE(core_->IsOpen(polarimeter_));
  EXPECT_TRUE(core_->IsOpen(epc_));
}

TEST_F(EmulatorCoreTest, AStreamSendsTheReadingsAtItsRateByItselfUntilStopped) {
  Start();
  Send(polarimeter_, ":MEAS:STREAM SOP 1000\n");  // taken without a reply
  EXPECT_EQ(Take(polarimeter_), "");
  EXPECT_EQ(core_->NextDueNs(), kStartNs + kMs);
  Wait(kMs - 1);
  EXPECT_EQ(Take(polarimeter_), "");
  Wait(1);
  std::string lines = Take(polarimeter_);
  ASSERT_EQ(std::count(lines.begin(), lines.end(), '\n'), 1) << lines;
  EXPECT_EQ(std::count(lines.begin(), lines.end(), ','), 2) << lines;  // s1,s2,s3
  Wait(5 * kMs);
  lines = Take(polarimeter_);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), 5) << lines;
  // A query still answers between the stream's lines; BOTH streams six numbers.
  EXPECT_EQ(Ask(polarimeter_, "*IDN?"), "dpc-emulator,POL,0,0.1");
  Send(polarimeter_, ":meas:stream both 100\n");
  Wait(10 * kMs);
  lines = Take(polarimeter_);
  ASSERT_EQ(std::count(lines.begin(), lines.end(), '\n'), 1) << lines;
  EXPECT_EQ(std::count(lines.begin(), lines.end(), ','), 5) << lines;  // S_in, S_out
  // A stall: at most kMaxStreamLinesPerOutput lines come at once, the rest are counted skipped.
  Wait(1000 * kMs);
  lines = Take(polarimeter_);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), EmulatorCore::kMaxStreamLinesPerOutput);
  EXPECT_EQ(core_->Status(now_ns_)["polarimeter"]["stream_skipped"], 100 - EmulatorCore::kMaxStreamLinesPerOutput);
  Send(polarimeter_, ":MEAS:STREAM OFF\n");
  Wait(100 * kMs);
  EXPECT_EQ(Take(polarimeter_), "");
  EXPECT_EQ(core_->NextDueNs(), INT64_MAX);
  // Bad starts are refused with the usage, and start nothing.
  for (const char* bad : {":MEAS:STREAM", ":MEAS:STREAM SOP", ":MEAS:STREAM SOP 0", ":MEAS:STREAM SOP 1e6",
                          ":MEAS:STREAM SOP nan", ":MEAS:STREAM XYZ 10", ":MEAS:STREAM SOP 10 20", ":MEAS:STREAMX"}) {
    EXPECT_EQ(Ask(polarimeter_, bad).rfind("ERR ", 0), 0u) << bad;
  }
  Wait(100 * kMs);
  EXPECT_EQ(Take(polarimeter_), "");
  // The EPC has no stream.
  EXPECT_EQ(Ask(epc_, ":MEAS:STREAM SOP 10"), "ERR unknown command");
}

TEST_F(EmulatorCoreTest, AStreamThatIsNotReadEndsItsSession) {
  Start();
  Send(polarimeter_, ":MEAS:STREAM BOTH 100000\n");
  for (int i = 0; i < 100'000 && core_->IsOpen(polarimeter_); ++i) {
    Wait(10'000);
    core_->Output(polarimeter_, now_ns_);  // produced, never written
  }
  EXPECT_FALSE(core_->IsOpen(polarimeter_));
  EXPECT_EQ(core_->Output(polarimeter_, now_ns_), "");
}

TEST_F(EmulatorCoreTest, AnInstrumentTakesAtMostItsSessionLimit) {
  Start();
  for (int i = 1; i < EmulatorCore::kMaxSessionsPerInstrument; ++i) ASSERT_TRUE(core_->Open(Instrument::kEpc, now_ns_));
  EXPECT_FALSE(core_->Open(Instrument::kEpc, now_ns_));
  core_->Close(epc_);
  EXPECT_TRUE(core_->Open(Instrument::kEpc, now_ns_));
  EXPECT_TRUE(core_->Open(Instrument::kPolarimeter, now_ns_));
}

/// Random bytes, and random sentences of the protocol's own words, into every instrument: the
/// emulator never crashes, never holds more than its bounds, and every reply it completes is a
/// line. The control port gets no words that would take the instruments away.
TEST_F(EmulatorCoreTest, RandomStreamsNeverCrashOrGrowIt) {
  EmulatorSettings settings;
  settings.latency_s = 0.002;
  ScenarioConfig scenario = EpcScenario();
  scenario.simulation.polarimeter_noise_deg = 0.5;
  Start(scenario, settings);
  std::mt19937_64 random(7);
  const std::vector<std::string> words = {
      ":SOUR", ":sour", "1", "3", "4", "0", "99999999999", ":VOLT", ":VOLT?", "?", " ", "\t", "\r", "\n", "\r\n",
      "-", "+", "1e400", "nan", "inf", "5.5", "-10", "10.0000001", "*IDN?", ":MEAS:SOP?", ":MEAS:BOTH?",
      ":MEAS:SIN?", std::string(1, '\0'), "\xff", "garbage", "truncate", "slow", "temperature", "status", "epc", "polarimeter",
      "0.001", "2", "help", "-273"};
  std::vector<std::optional<EmulatorCore::SessionId>> sessions = {epc_, polarimeter_, control_};
  for (int round = 0; round < 20'000; ++round) {
    const int which = static_cast<int>(random() % 3);
    if (!sessions[which] || !core_->IsOpen(*sessions[which])) {
      sessions[which] = core_->Open(which == 0 ? Instrument::kEpc : which == 1 ? Instrument::kPolarimeter
                                                                                : Instrument::kControl,
                                    now_ns_);
      ASSERT_TRUE(sessions[which]);
    }
    std::string bytes;
    const int pieces = 1 + static_cast<int>(random() % 12);
    for (int p = 0; p < pieces; ++p) {
      if (random() % 2 == 0) {
        bytes += words[random() % words.size()];
      } else {
        bytes.push_back(static_cast<char>(random() & 0xff));
      }
    }
    if (round % 100 == 0) bytes += std::string(random() % 600, 'x');
    Send(*sessions[which], bytes);
    if (random() % 4 != 0) {  // some clients read, some do not
      for (auto& session : sessions) {
        if (!session || !core_->IsOpen(*session)) continue;
        const std::string out = Take(*session);
        EXPECT_LE(out.size(), EmulatorCore::kMaxQueuedBytes);
      }
    }
    Wait(static_cast<int64_t>(random() % (2 * kMs)));
    core_->TakeEnded();
  }
  // Still answering, and still itself.
  for (auto& session : sessions) {
    if (session) core_->Close(*session);
  }
  const EmulatorCore::SessionId epc = *core_->Open(Instrument::kEpc, now_ns_);
  control_ = *core_->Open(Instrument::kControl, now_ns_);
  EXPECT_EQ(Ask(control_, "garbage epc 0"), "OK garbage epc: the next 0 replies");
  Ask(control_, "truncate epc 0");
  Ask(control_, "slow epc 0 0");
  Send(epc, "\n");
  Wait(10 * kMs);
  Take(epc);
  Send(epc, "*IDN?\n");
  Wait(10 * kMs);
  EXPECT_EQ(Take(epc), "dpc-emulator,EPC,3,0.1\n");
  EXPECT_TRUE(Status().is_object());
}

}  // namespace
}  // namespace dpc::services
