#include "controller_core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_config.h"
#include "dpc/optics/rotation.h"

namespace dpc::services {
namespace {

msg::StokesSample Sample(uint64_t sequence, std::array<double, 3> s_in, bool lockstep = false) {
  msg::StokesSample s;
  s.bench_id("bench1");
  s.sequence_number(sequence);
  s.s_in(s_in);
  s.s_out(s_in);
  s.lockstep(lockstep);
  return s;
}

msg::WaveplateState State(std::vector<double> phi, const std::string& obeyed, uint64_t answers,
                          msg::DriverMode mode = msg::DRIVER_ACTIVE) {
  msg::WaveplateState s;
  s.bench_id("bench1");
  s.phi_applied(std::move(phi));
  s.saturated(std::vector<bool>(3, false));
  s.mode(mode);
  s.obeyed_controller_id(obeyed);
  s.answers_sample(answers);
  return s;
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
    ASSERT_EQ(core_.OnDevice(bus::DescribeDevice(StagesFromAxes("131"), "bench1", "driver", 0.0)), "");
    ASSERT_EQ(core_.OnTarget(bus::TargetMessage(TargetConfig{}, "bench1", 1, "")), "");
  }
  ControllerCore core_;
  int64_t now_ns_ = 1'000'000;
};

TEST_F(ControllerCoreTest, AnswersNothingUntilDeviceTargetAndStateArrived) {
  EXPECT_FALSE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  Configure();
  EXPECT_FALSE(core_.OnSample(Sample(2, {1, 0, 0}), now_ns_, 0));
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));
  auto command = core_.OnSample(Sample(3, {1, 0, 0}), now_ns_, 0);
  ASSERT_NE(command, nullptr);
  EXPECT_EQ(command->answers_sample(), 3u);
  EXPECT_EQ(command->phi().size(), 3u);
  EXPECT_EQ(command->controller_id().to_string(), "me");
}

TEST_F(ControllerCoreTest, RefusesAnUnusableDeviceDescription) {
  msg::DeviceDescription description = bus::DescribeDevice(StagesFromAxes("131"), "bench1", "driver", 0.0);
  description.stages()[0].axis({0, 0, 0});
  EXPECT_NE(core_.OnDevice(description).find("axis"), std::string::npos);
  EXPECT_FALSE(core_.configured());
}

TEST_F(ControllerCoreTest, RejectsMalformedSamplesAndCountsThem) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));
  EXPECT_FALSE(core_.OnSample(Sample(1, {1, 1, 0}), now_ns_, 0));
  EXPECT_FALSE(core_.OnSample(Sample(2, {NAN, 0, 0}), now_ns_, 0));
  EXPECT_FALSE(core_.OnSample(Sample(0, {1, 0, 0}), now_ns_, 0));
  EXPECT_EQ(core_.rejected_samples(), 3u);
  EXPECT_NE(core_.last_rejection().find("sequence"), std::string::npos);
}

TEST_F(ControllerCoreTest, RefusesMalformedStatesWithoutTouchingItsPhi) {
  Configure();
  core_.OnState(State({0.1, 0.2, 0.3}, "", 0, msg::DRIVER_HOLDING));
  core_.OnState(State({0.1, NAN, 0.3}, "other", 1));
  core_.OnState(State({0.1, 0.2}, "other", 1));
  EXPECT_EQ(core_.rejected_samples(), 2u);
  EXPECT_NE(core_.last_rejection().find("phi_applied has 2 values"), std::string::npos);
  EXPECT_EQ(core_.phi(), (ControlVector(3) << 0.1, 0.2, 0.3).finished());
}

TEST_F(ControllerCoreTest, WhileStandbyItFollowsTheAppliedPhi) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));
  ASSERT_TRUE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  // Another controller is obeyed and applies something else: we follow it.
  core_.OnState(State({0.4, -0.3, 0.2}, "other", 1));
  EXPECT_FALSE(core_.obeyed());
  EXPECT_EQ(core_.phi(), (ControlVector(3) << 0.4, -0.3, 0.2).finished());
  // Once obeyed, our own integrator goes on (a state of our latest command does not reset it).
  auto command = core_.OnSample(Sample(2, {1, 0, 0}), now_ns_ + 100'000, 0);
  ASSERT_NE(command, nullptr);
  core_.OnState(State(command->phi(), "me", 2));
  EXPECT_TRUE(core_.obeyed());
  auto next = core_.OnSample(Sample(3, {1, 0, 0}), now_ns_ + 200'000, 0);
  ASSERT_NE(next, nullptr);
  core_.OnState(State({0, 0, 0}, "me", 2));  // a late state of an older command
  EXPECT_EQ(core_.phi(), Eigen::Map<const ControlVector>(next->phi().data(), 3));
}

TEST_F(ControllerCoreTest, InLockstepAStaleHoldingHeartbeatDoesNotUndoTheLatestCommand) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));
  auto command = core_.OnSample(Sample(1, {1, 0, 0}, /*lockstep=*/true), now_ns_, 0);
  ASSERT_NE(command, nullptr);
  const ControlVector issued = core_.phi();
  ASSERT_GT(issued.norm(), 0.0);
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));  // sent before the driver saw it
  EXPECT_EQ(core_.phi(), issued);
}

TEST_F(ControllerCoreTest, ReportsFrozenWhenSamplesStop) {
  Configure();
  core_.OnState(State({0, 0, 0}, "", 0, msg::DRIVER_HOLDING));
  ASSERT_TRUE(core_.OnSample(Sample(1, {1, 0, 0}), now_ns_, 0));
  const msg::ControllerStatus status = core_.TakeStatus(now_ns_ + 100'000'000, 0, 0);
  EXPECT_NE(status.condition().to_string().find("frozen"), std::string::npos) << status.condition().to_string();
  EXPECT_EQ(status.updates(), 1u);
}

}  // namespace
}  // namespace dpc::services

namespace dpc::services {
namespace {

// Delay compensation in real time: a closed loop without DDS. The input turns about a tilted
// axis at 300 rad/s; samples come every ~100 µs with jitter; the driver applies each command
// `delay` samples after the sample it answers. The controller measures that latency from the
// sample timestamps and predicts across it.
struct RealTimeLoopResult {
  double mean_error_deg = 0.0;
  double horizon_s = 0.0;
  std::string condition;
};

RealTimeLoopResult RunRealTimeLoop(bool predict, int delay_samples) {
  ControllerSettings settings = Settings();
  if (predict) settings.controller.prediction = PredictionConfig{};
  ControllerCore core(settings);
  const auto stages = StagesFromAxes("131");
  EXPECT_EQ(core.OnDevice(bus::DescribeDevice(stages, "bench1", "driver", 0.0)), "");
  EXPECT_EQ(core.OnTarget(bus::TargetMessage(TargetConfig{}, "bench1", 1, "")), "");
  const WaveplateChain chain = BuildChain(stages);
  const Target target = BuildTarget(TargetConfig{});
  const Vector3 axis = Vector3(0.3, 0.2, 1.0).normalized();
  const double rate_rad_per_s = 300.0;
  StokesVector s0(1.0, 0.0, 0.0);
  s0 = (s0 - axis.dot(s0) * axis).normalized();

  std::vector<ControlVector> commands(1, ControlVector::Zero(3));  // commands[k]: answers sample k
  core.OnState(State({0, 0, 0}, "me", 0));
  int64_t t_ns = 1'000'000'000;
  double error_sum_deg = 0.0;
  int counted = 0;
  const int samples = 6000;
  for (int k = 1; k <= samples; ++k) {
    t_ns += 100'000 + ((k * 7919) % 21 - 10) * 2'000;  // 100 µs ± 20 µs
    const double t_s = static_cast<double>(t_ns - 1'000'000'000) * 1e-9;
    const StokesVector s_in = RotationAboutAxis(axis, rate_rad_per_s * t_s) * s0;
    // The φ applied now: the command answering sample k − delay (or the latest before it).
    const int answered = std::max(0, std::min<int>(k - delay_samples, static_cast<int>(commands.size()) - 1));
    const ControlVector& applied = commands[static_cast<size_t>(answered)];
    const StokesVector s_out = chain.Output(applied, s_in);
    if (k > samples / 2) {
      error_sum_deg += target.DistanceRad(s_out) * 180.0 / M_PI;
      ++counted;
    }
    // The driver's state for that command reaches the controller first.
    core.OnState(State({applied[0], applied[1], applied[2]}, "me", static_cast<uint64_t>(answered)));
    msg::StokesSample sample = Sample(static_cast<uint64_t>(k), {s_in[0], s_in[1], s_in[2]});
    sample.s_out({s_out[0], s_out[1], s_out[2]});
    sample.sample_time_ns(t_ns);
    const msg::WaveplateCommand* command = core.OnSample(sample, t_ns, t_ns);
    EXPECT_NE(command, nullptr);
    if (command == nullptr) break;
    commands.emplace_back(Eigen::Map<const ControlVector>(command->phi().data(), 3));
  }
  RealTimeLoopResult result;
  result.mean_error_deg = error_sum_deg / counted;
  result.horizon_s = core.prediction_horizon_s();
  result.condition = core.TakeStatus(t_ns, t_ns, 0).condition().to_string();
  return result;
}

TEST(ControllerCoreRealTimePredictionTest, MeasuresTheLoopLatencyAndPredictsAcrossIt) {
  const RealTimeLoopResult plain = RunRealTimeLoop(false, 3);
  const RealTimeLoopResult predicted = RunRealTimeLoop(true, 3);
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

}  // namespace
}  // namespace dpc::services
