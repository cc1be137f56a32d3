#include "controller_core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_config.h"
#include "dpc/optics/rotation.h"

namespace dpc::services {
namespace {

BenchSample Sample(uint64_t sequence, std::array<double, 3> s_in, bool lockstep = false) {
  BenchSample s;
  s.sequence = sequence;
  s.s_in = StokesVector(s_in[0], s_in[1], s_in[2]);
  s.s_out = s.s_in;
  s.lockstep = lockstep;
  return s;
}

DriverState State(const ControlVector& phi, const std::string& obeyed, uint64_t answers,
                  DriverMode mode = DriverMode::kActive) {
  DriverState s;
  s.motion = WaveplateMotion::Still(phi);
  s.mode = mode;
  s.obeyed_controller_id = obeyed;
  s.answers_sample = answers;
  return s;
}

DriverState State(std::initializer_list<double> phi, const std::string& obeyed, uint64_t answers,
                  DriverMode mode = DriverMode::kActive) {
  ControlVector v(static_cast<Eigen::Index>(phi.size()));
  Eigen::Index i = 0;
  for (double x : phi) v[i++] = x;
  return State(v, obeyed, answers, mode);
}

DeviceDescription Device(std::vector<StageConfig> stages, double max_ramp_s = 0.0) {
  DeviceDescription device;
  device.driver_id = "driver";
  device.stages = std::move(stages);
  device.max_ramp_s = max_ramp_s;
  return device;
}

BenchTarget FirstTarget() {
  BenchTarget target;
  target.revision = 1;
  return target;
}

/// Controller "me": gradient projection, step 0.5, a 10 kHz bench.
ControllerSettings Settings() {
  ControllerSettings settings;
  settings.controller_id = "me";
  settings.controller.step = 0.5;
  settings.simulation.sample_rate_hz = 10e3;
  settings.simulation.delay_s = 1e-4;
  settings.simulation.duration_s = 1.0;
  settings.controller.dither.reset_duration_s = 1e-4;
  return settings;
}

class ControllerCoreTest : public ::testing::Test {
 protected:
  ControllerCoreTest() : core_(Settings()) {}
  void Configure() {
    ASSERT_EQ(core_.OnDevice(Device(StagesFromAxes("131"))), "");
    ASSERT_EQ(core_.OnTarget(FirstTarget()), "");
  }
  ControllerCore core_;
  int64_t now_ns_ = 1'000'000;
};

TEST_F(ControllerCoreTest, AnswersNothingUntilDeviceTargetAndStateArrived) {
  EXPECT_FALSE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  Configure();
  EXPECT_FALSE(core_.OnSample(Sample(2, {1, 0, 0}), now_ns_, 0));
  core_.OnState(State({0, 0, 0}, "", 0, DriverMode::kHolding));
  auto command = core_.OnSample(Sample(3, {1, 0, 0}), now_ns_, 0);
  ASSERT_NE(command, nullptr);
  EXPECT_EQ(command->answers_sample, 3u);
  EXPECT_EQ(command->phi.size(), 3);
  EXPECT_EQ(command->controller_id, "me");
}

TEST_F(ControllerCoreTest, RefusesADeviceItsLawDoesNotFit) {
  ControllerSettings settings = Settings();
  settings.controller.method = ControlMethod::kInverse;  // a square task: 3 controls
  ControllerCore core(settings);
  EXPECT_NE(core.OnDevice(Device(StagesFromAxes("3131"))).find("controller.method"), std::string::npos);
  EXPECT_FALSE(core.configured());
  core.OnUnusableDevice("device.stages[0].axis: zero");
  EXPECT_NE(core.TakeStatus(0, 0, 0).condition.find("unusable device description: device.stages[0].axis"),
            std::string::npos);
}

TEST_F(ControllerCoreTest, RefusesADeviceWithoutTheRangesItsCriterionOrThresholdNeeds) {
  // The controller's own scenario may have ranges (it was validated with them), but the
  // driver's device decides: the range criterion on a device without ranges, or a gpt threshold
  // that the device's ranges never let the controls reach, would run as something else.
  ControllerSettings settings = Settings();
  settings.controller.nullspace_criterion = NullspaceCriterion::kRange;
  ControllerCore ranged(settings);
  std::vector<StageConfig> stages = StagesFromAxes("131");
  EXPECT_NE(ranged.OnDevice(Device(stages)).find("controller.nullspace_criterion: RANGE keeps the controls "
                                                 "inside their ranges, but no stage has a range"),
            std::string::npos);
  EXPECT_FALSE(ranged.configured());
  for (StageConfig& stage : stages) stage.range = ControlRange{-1.0, 1.0};
  EXPECT_EQ(ranged.OnDevice(Device(stages)), "");

  settings = Settings();
  settings.controller.method = ControlMethod::kThresholdedGradientProjection;
  settings.controller.threshold = 1.0;
  ControllerCore thresholded(settings);
  EXPECT_NE(thresholded.OnDevice(Device(stages)).find("controller.threshold: gpt runs the null-space term"),
            std::string::npos);
  EXPECT_NE(thresholded.TakeStatus(0, 0, 0).condition.find("unusable device description: controller.threshold"),
            std::string::npos);
  EXPECT_EQ(thresholded.OnDevice(Device(StagesFromAxes("131"))), "");
}

TEST_F(ControllerCoreTest, CountsAndReportsWhatTheEdgeRefusedWithoutTouchingItsPhi) {
  // (Which samples and states are malformed is bus::ReadSample / ReadState's business.)
  Configure();
  core_.OnState(State({0.1, 0.2, 0.3}, "", 0, DriverMode::kHolding));
  core_.RejectInput("s_in = [1, 1, 0] is not a unit Stokes vector");
  core_.RejectInput("state: phi_applied has 2 values, the device has 3 controls");
  EXPECT_EQ(core_.rejected_samples(), 2u);
  EXPECT_NE(core_.last_rejection().find("phi_applied has 2 values"), std::string::npos);
  EXPECT_EQ(core_.phi(), (ControlVector(3) << 0.1, 0.2, 0.3).finished());
  EXPECT_EQ(core_.TakeStatus(0, 0, 0).rejected_samples, 2u);
}

TEST_F(ControllerCoreTest, WhileStandbyItFollowsTheAppliedPhi) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, DriverMode::kHolding));
  ASSERT_TRUE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  // Another controller is obeyed and applies something else: we follow it.
  core_.OnState(State({0.4, -0.3, 0.2}, "other", 1));
  EXPECT_FALSE(core_.obeyed());
  EXPECT_EQ(core_.phi(), (ControlVector(3) << 0.4, -0.3, 0.2).finished());
  // Once obeyed, our own integrator goes on (a state of our latest command does not reset it).
  auto command = core_.OnSample(Sample(2, {1, 0, 0}), now_ns_ + 100'000, 0);
  ASSERT_NE(command, nullptr);
  core_.OnState(State(command->phi, "me", 2));
  EXPECT_TRUE(core_.obeyed());
  auto next = core_.OnSample(Sample(3, {1, 0, 0}), now_ns_ + 200'000, 0);
  ASSERT_NE(next, nullptr);
  core_.OnState(State({0, 0, 0}, "me", 2));  // a late state of an older command
  EXPECT_EQ(core_.phi(), next->phi);
}

TEST_F(ControllerCoreTest, InLockstepAStaleHoldingHeartbeatDoesNotUndoTheLatestCommand) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, DriverMode::kHolding));
  auto command = core_.OnSample(Sample(1, {1, 0, 0}, /*lockstep=*/true), now_ns_, 0);
  ASSERT_NE(command, nullptr);
  const ControlVector issued = core_.phi();
  ASSERT_GT(issued.norm(), 0.0);
  core_.OnState(State({0, 0, 0}, "", 0, DriverMode::kHolding));  // sent before the driver saw it
  EXPECT_EQ(core_.phi(), issued);
}

TEST_F(ControllerCoreTest, ReportsFrozenWhenSamplesStop) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, DriverMode::kHolding));
  ASSERT_TRUE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  const ControllerStatusReport status = core_.TakeStatus(now_ns_ + 100'000'000, 0, 0);
  EXPECT_NE(status.condition.find("frozen"), std::string::npos) << status.condition;
  EXPECT_EQ(status.updates, 1u);
}

}  // namespace
}  // namespace dpc::services

namespace dpc::services {
namespace {

// Delay compensation in real time: a closed loop without DDS. The input turns about a tilted
// axis at 300 rad/s; samples come every ~100 µs with jitter; the driver applies each command
// `delay` samples after the sample it answers (or a delay that varies between delay and
// max_delay). The controller measures that latency from the sample timestamps and predicts
// across it (kLatency), or sends rates that a ramping driver follows (kRamp).
struct RealTimeLoopResult {
  double mean_error_deg = 0.0;
  double horizon_s = 0.0;
  std::string condition;
  ControlVector last_rate;
};

struct RealTimeLoopOptions {
  bool predict = false;
  PredictionMode mode = PredictionMode::kLatency;
  int delay_samples = 3;
  int max_delay_samples = 3;     ///< > delay_samples: each sample's delay varies in between
  double rate_rad_per_s = 300.0;
};

RealTimeLoopResult RunRealTimeLoop(const RealTimeLoopOptions& options) {
  ControllerSettings settings = Settings();
  if (options.predict) settings.controller.prediction = PredictionConfig{};
  settings.prediction_mode = options.mode;
  ControllerCore core(settings);
  const auto stages = StagesFromAxes("131");
  const double max_ramp_s = 2e-3;  // the driver's (DriverSettings' default)
  EXPECT_EQ(core.OnDevice(Device(stages, max_ramp_s)), "");
  EXPECT_EQ(core.OnTarget(FirstTarget()), "");
  const WaveplateChain chain = BuildChain(stages);
  const Target target = BuildTarget(TargetConfig{});
  const Vector3 axis = Vector3(0.3, 0.2, 1.0).normalized();
  StokesVector s0(1.0, 0.0, 0.0);
  s0 = (s0 - axis.dot(s0) * axis).normalized();

  // commands[j]: the command answering sample j (φ at its sample time t[j], rate).
  struct Sent {
    ControlVector phi, rate;
    int64_t t_ns = 0;
  };
  std::vector<Sent> commands(1, Sent{ControlVector::Zero(3), ControlVector::Zero(3), 0});
  core.OnState(State({0, 0, 0}, "me", 0));
  int64_t t_ns = 1'000'000'000;
  double error_sum_deg = 0.0;
  int counted = 0;
  int answered = 0;
  const int samples = 6000;
  for (int k = 1; k <= samples; ++k) {
    t_ns += 100'000 + ((k * 7919) % 21 - 10) * 2'000;  // 100 µs ± 20 µs
    const double t_s = static_cast<double>(t_ns - 1'000'000'000) * 1e-9;
    const StokesVector s_in = RotationAboutAxis(axis, options.rate_rad_per_s * t_s) * s0;
    // The command applied now: the one answering sample k − delay (or the latest before it);
    // the delay of a jittery loop varies from sample to sample.
    const int spread = options.max_delay_samples - options.delay_samples + 1;
    const int delay = options.delay_samples + (k * 104729 / 7) % spread;
    answered = std::max(answered, std::max(0, std::min<int>(k - delay, static_cast<int>(commands.size()) - 1)));
    const Sent& applied = commands[static_cast<size_t>(answered)];
    // The driver's ramp, evaluated by the bench at this sample's time.
    const double ramp_s = std::clamp(static_cast<double>(t_ns - applied.t_ns) * 1e-9, 0.0, max_ramp_s);
    const ControlVector phi_now = applied.phi + applied.rate * ramp_s;
    const StokesVector s_out = chain.Output(phi_now, s_in);
    if (k > samples / 2) {
      error_sum_deg += target.DistanceRad(s_out) * 180.0 / M_PI;
      ++counted;
    }
    // The driver's state for that command reaches the controller first.
    DriverState state = State(applied.phi, "me", static_cast<uint64_t>(answered));
    if (!applied.rate.isZero()) {
      state.motion.rate_per_s = applied.rate;
      state.motion.start_ns = applied.t_ns;
      state.motion.end_ns = applied.t_ns + static_cast<int64_t>(max_ramp_s * 1e9);
      state.motion.moving = true;
    }
    core.OnState(state);
    BenchSample sample = Sample(static_cast<uint64_t>(k), {s_in[0], s_in[1], s_in[2]});
    sample.s_out = s_out;
    sample.time_ns = t_ns;
    const ControllerCommand* command = core.OnSample(sample, t_ns, t_ns);
    EXPECT_NE(command, nullptr);
    if (command == nullptr) break;
    Sent sent{command->phi, ControlVector::Zero(3), t_ns};
    if (command->rate_per_s.size() != 0) {
      EXPECT_EQ(command->rate_per_s.size(), 3);
      sent.rate = command->rate_per_s;
    }
    commands.push_back(sent);
  }
  RealTimeLoopResult result;
  result.mean_error_deg = error_sum_deg / counted;
  result.horizon_s = core.prediction_horizon_s();
  result.condition = core.TakeStatus(t_ns, t_ns, 0).condition;
  result.last_rate = commands.back().rate;
  return result;
}

TEST(ControllerCoreRealTimePredictionTest, MeasuresTheLoopLatencyAndPredictsAcrossIt) {
  const RealTimeLoopResult plain = RunRealTimeLoop({});
  const RealTimeLoopResult predicted = RunRealTimeLoop({.predict = true});
  std::printf("300 rad/s, 3 samples of delay: mean error %.3f° plain, %.4f° predicted (horizon %.1f µs)\n",
              plain.mean_error_deg, predicted.mean_error_deg, predicted.horizon_s * 1e6);
  // The horizon: 3 sample intervals of ~100 µs.
  EXPECT_NEAR(predicted.horizon_s, 300e-6, 30e-6);
  EXPECT_NE(predicted.condition.find("predicting 0.3"), std::string::npos) << predicted.condition;
  EXPECT_NE(predicted.condition.find("300 rad/s"), std::string::npos) << predicted.condition;
  // 300 rad/s with 3 samples of delay: ~0.1 rad moves in flight. Prediction removes most of it.
  EXPECT_GT(plain.mean_error_deg, 2.0);
  EXPECT_LT(predicted.mean_error_deg, 0.1 * plain.mean_error_deg)
      << "plain " << plain.mean_error_deg << "°, predicted " << predicted.mean_error_deg << "°";
}


// With a loop delay that jitters between 2 and 4 samples no single horizon fits; the rate
// commands (kRamp) make the delay irrelevant, so the error is far below kLatency's.
TEST(ControllerCoreRealTimePredictionTest, RateCommandsTrackThroughAJitteringDelay) {
  const RealTimeLoopResult plain = RunRealTimeLoop({.delay_samples = 2, .max_delay_samples = 4});
  const RealTimeLoopResult latency = RunRealTimeLoop(
      {.predict = true, .mode = PredictionMode::kLatency, .delay_samples = 2, .max_delay_samples = 4});
  const RealTimeLoopResult ramp = RunRealTimeLoop(
      {.predict = true, .mode = PredictionMode::kRamp, .delay_samples = 2, .max_delay_samples = 4});
  std::printf("300 rad/s, 2–4 samples of delay: mean error %.3f° plain, %.4f° latency, %.5f° ramp\n",
              plain.mean_error_deg, latency.mean_error_deg, ramp.mean_error_deg);
  EXPECT_NE(ramp.condition.find("ramping with the input at 300 rad/s"), std::string::npos) << ramp.condition;
  // The rate of a 300 rad/s input on θ = πφ stages: of order 300/π per second.
  ASSERT_EQ(ramp.last_rate.size(), 3);
  EXPECT_GT(ramp.last_rate.norm(), 10.0);
  EXPECT_LT(ramp.last_rate.norm(), 1000.0);
  EXPECT_GT(plain.mean_error_deg, 2.0);
  EXPECT_LT(ramp.mean_error_deg, 0.25 * latency.mean_error_deg)
      << "latency " << latency.mean_error_deg << "°, ramp " << ramp.mean_error_deg << "°";
  EXPECT_LT(ramp.mean_error_deg, 0.15);  // measured 0.092°
}

// A driver that does not ramp (device description max_ramp_s = 0) gets points: the controller
// falls back to predicting across the latency.
TEST(ControllerCoreRealTimePredictionTest, WithoutARampingDriverItSendsNoRate) {
  ControllerSettings settings = Settings();
  settings.controller.prediction = PredictionConfig{};
  ControllerCore core(settings);
  ASSERT_EQ(core.OnDevice(Device(StagesFromAxes("131"), 0.0)), "");
  ASSERT_EQ(core.OnTarget(FirstTarget()), "");
  core.OnState(State({0, 0, 0}, "me", 0));
  const Vector3 axis(0.0, 0.0, 1.0);
  for (int k = 1; k <= 100; ++k) {
    const StokesVector s_in = RotationAboutAxis(axis, 0.03 * k) * StokesVector(1.0, 0.0, 0.0);
    BenchSample sample = Sample(static_cast<uint64_t>(k), {s_in[0], s_in[1], s_in[2]});
    sample.time_ns = k * 100'000;
    const ControllerCommand* command = core.OnSample(sample, k * 100'000, k * 100'000);
    ASSERT_NE(command, nullptr);
    EXPECT_EQ(command->rate_per_s.size(), 0);
  }
  EXPECT_NE(core.TakeStatus(0, 0, 0).condition.find("predicting"), std::string::npos);
}

// A standby controller follows the applied motion where it is at each sample, so its first
// obeyed command continues from there.
TEST(ControllerCoreRealTimePredictionTest, AStandbyFollowsTheRampAtTheSampleTime) {
  ControllerSettings settings = Settings();
  settings.controller.step = 1e-9;          // the law's Δφ vanishes: φ shows what it follows
  settings.controller.nullspace_step = 0.0;
  ControllerCore core(settings);
  ASSERT_EQ(core.OnDevice(Device(StagesFromAxes("131"), 2e-3)), "");
  ASSERT_EQ(core.OnTarget(FirstTarget()), "");
  DriverState state = State({0.1, 0.2, 0.3}, "other", 1);
  state.motion.rate_per_s = (ControlVector(3) << 10.0, 0.0, -10.0).finished();
  state.motion.start_ns = 1'000'000;
  state.motion.end_ns = 3'000'000;
  state.motion.moving = true;
  core.OnState(state);
  BenchSample sample = Sample(2, {1.0, 0.0, 0.0});
  sample.time_ns = 1'500'000;  // 0.5 ms into the ramp
  ASSERT_NE(core.OnSample(sample, 1'500'000, 1'500'000), nullptr);
  EXPECT_NEAR(core.phi()[0], 0.105, 1e-6);
  EXPECT_NEAR(core.phi()[2], 0.295, 1e-6);
  BenchSample later = Sample(3, {1.0, 0.0, 0.0});
  later.time_ns = 9'000'000;  // after the ramp's end
  ASSERT_NE(core.OnSample(later, 9'000'000, 9'000'000), nullptr);
  EXPECT_NEAR(core.phi()[0], 0.12, 1e-6);   // where the ramp stopped
  EXPECT_NEAR(core.phi()[2], 0.28, 1e-6);
}

}  // namespace
}  // namespace dpc::services
