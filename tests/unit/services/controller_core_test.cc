#include "controller_core.h"

#include <gtest/gtest.h>

#include <cmath>

#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_config.h"

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

class ControllerCoreTest : public ::testing::Test {
 protected:
  ControllerCoreTest() : core_(Settings()) {}
  static ControllerSettings Settings() {
    ControllerSettings settings;
    settings.controller_id = "me";
    settings.controller.step = 0.5;
    settings.simulation.sample_rate_hz = 10e3;
    settings.simulation.delay_s = 1e-4;
    settings.simulation.duration_s = 1.0;
    settings.controller.dither.reset_duration_s = 1e-4;
    return settings;
  }
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
