#include "dpc/bus/message_conversion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dpc/config/scenario_error.h"

namespace dpc::bus {
namespace {

TEST(CheckUnitStokes, AcceptsUnitRefusesNonUnitAndNonFinite) {
  EXPECT_EQ(CheckUnitStokes({0.0, 0.6, 0.8}, "s_in"), "");
  EXPECT_NE(CheckUnitStokes({1.0, 1.0, 0.0}, "s_in").find("not a unit Stokes vector"), std::string::npos);
  EXPECT_NE(CheckUnitStokes({NAN, 0.0, 0.0}, "s_out").find("s_out"), std::string::npos);
  EXPECT_NE(CheckUnitStokes({INFINITY, 0.0, 0.0}, "s_in").find("not finite"), std::string::npos);
}

TEST(ReadSample, ReadsAUsableSampleAndNamesWhatIsWrongWithAnother) {
  BenchSample sample;
  sample.sequence = 7;
  sample.time_ns = 1'000;
  sample.publish_time_ns = 2'000;
  sample.s_in = StokesVector(0.0, 0.6, 0.8);
  sample.s_out = StokesVector(1.0, 0.0, 0.0);
  sample.optical_power_w = 1e-3;
  sample.lockstep = true;
  msg::StokesSample m;
  WriteSample(sample, "b", &m);
  EXPECT_EQ(m.bench_id().to_string(), "b");
  BenchSample back;
  ASSERT_EQ(ReadSample(m, &back), "");
  EXPECT_EQ(back.sequence, 7u);
  EXPECT_EQ(back.time_ns, 1'000);
  EXPECT_EQ(back.publish_time_ns, 2'000);
  EXPECT_EQ(back.s_in, sample.s_in);
  EXPECT_EQ(back.s_out, sample.s_out);
  EXPECT_EQ(back.optical_power_w, 1e-3);
  EXPECT_TRUE(back.lockstep);
  m.s_in({1.0, 1.0, 0.0});
  EXPECT_NE(ReadSample(m, &back).find("s_in"), std::string::npos);
  m.s_in({0.0, 0.6, 0.8});
  m.s_out({NAN, 0.0, 0.0});
  EXPECT_NE(ReadSample(m, &back).find("s_out"), std::string::npos);
  m.s_out({1.0, 0.0, 0.0});
  m.optical_power_w(-1.0);
  EXPECT_NE(ReadSample(m, &back).find("optical_power_w"), std::string::npos);
  m.optical_power_known(false);
  m.sequence_number(0);
  EXPECT_NE(ReadSample(m, &back).find("sequence_number 0"), std::string::npos);
}

TEST(ReadCommand, ReadsAUsableCommandAndNamesWhatIsWrongWithAnother) {
  msg::WaveplateCommand c;
  c.controller_id("A");
  c.answers_sample(9);
  c.phi({0.1, 0.2, 0.3});
  ControllerCommand read;
  EXPECT_EQ(ReadCommand(c, 3, &read), "");
  EXPECT_EQ(read.phi, (ControlVector(3) << 0.1, 0.2, 0.3).finished());
  EXPECT_EQ(read.rate_per_s.size(), 0);
  EXPECT_NE(ReadCommand(c, 4, &read).find("the device has 4 controls"), std::string::npos);
  c.phi(std::vector<double>(17, 0.0));
  EXPECT_NE(ReadCommand(c, 3, &read).find("oversized"), std::string::npos);
  EXPECT_EQ(read.controller_id, "A") << "read even when refused, for the report";
  EXPECT_EQ(read.answers_sample, 9u);
  c.phi({0.1, NAN, 0.3});
  EXPECT_NE(ReadCommand(c, 3, &read).find("phi[1]"), std::string::npos);
  c.phi({0.1, 0.2, 0.3});
  c.controller_id("");
  EXPECT_NE(ReadCommand(c, 3, &read).find("controller_id"), std::string::npos);
  c.controller_id("A");
  c.phi_rate_per_s({1.0, 2.0, 3.0});
  EXPECT_EQ(ReadCommand(c, 3, &read), "");
  EXPECT_EQ(read.rate_per_s, (ControlVector(3) << 1.0, 2.0, 3.0).finished());
  c.phi_rate_per_s({1.0, 2.0});
  EXPECT_NE(ReadCommand(c, 3, &read).find("phi_rate_per_s has 2 values"), std::string::npos);
  c.phi_rate_per_s({1.0, INFINITY, 3.0});
  EXPECT_NE(ReadCommand(c, 3, &read).find("phi_rate_per_s[1]"), std::string::npos);
}

TEST(WriteCommand, RoundTripsEveryField) {
  ControllerCommand command;
  command.controller_id = "main";
  command.priority = -3;
  command.sequence = 11;
  command.answers_sample = 12;
  command.sample_time_ns = 13;
  command.sample_publish_time_ns = 14;
  command.publish_time_ns = 15;
  command.phi = (ControlVector(2) << 0.5, -0.5).finished();
  command.rate_per_s = (ControlVector(2) << 3.0, 4.0).finished();
  msg::WaveplateCommand m;
  WriteCommand(command, "b", &m);
  EXPECT_EQ(m.bench_id().to_string(), "b");
  ControllerCommand back;
  ASSERT_EQ(ReadCommand(m, 2, &back), "");
  EXPECT_EQ(back.controller_id, "main");
  EXPECT_EQ(back.priority, -3);
  EXPECT_EQ(back.sequence, 11u);
  EXPECT_EQ(back.answers_sample, 12u);
  EXPECT_EQ(back.sample_time_ns, 13);
  EXPECT_EQ(back.sample_publish_time_ns, 14);
  EXPECT_EQ(back.publish_time_ns, 15);
  EXPECT_EQ(back.phi, command.phi);
  EXPECT_EQ(back.rate_per_s, command.rate_per_s);
}

TEST(ReadState, NamesTheProblem) {
  msg::WaveplateState s;
  DriverState read;
  s.phi_applied({0.1, 0.2, 0.3});
  EXPECT_EQ(ReadState(s, 3, &read), "");
  EXPECT_NE(ReadState(s, 2, &read).find("phi_applied has 3 values"), std::string::npos);
  s.phi_applied({0.1, NAN, 0.3});
  EXPECT_NE(ReadState(s, 3, &read).find("phi_applied[1]"), std::string::npos);
  s.phi_applied({0.1, 0.2, 0.3});
  s.phi_rate_per_s({1.0});
  EXPECT_NE(ReadState(s, 3, &read).find("phi_rate_per_s has 1 values"), std::string::npos);
  s.phi_rate_per_s({1.0, 0.0, NAN});
  EXPECT_NE(ReadState(s, 3, &read).find("phi_rate_per_s[2]"), std::string::npos);
  s.phi_rate_per_s({1.0, 0.0, -2.0});
  s.ramp_start_time_ns(5'000'000);
  s.ramp_end_time_ns(4'000'000);
  EXPECT_NE(ReadState(s, 3, &read).find("ramp_end_time_ns"), std::string::npos);
  // A ramp across the whole int64 range would overflow t − start in every reader.
  s.ramp_start_time_ns(std::numeric_limits<int64_t>::min());
  s.ramp_end_time_ns(std::numeric_limits<int64_t>::max());
  EXPECT_NE(ReadState(s, 3, &read).find("longer than any driver ramps"), std::string::npos);
  s.ramp_start_time_ns(0);
  s.ramp_end_time_ns(1'000'000'000);
  EXPECT_EQ(ReadState(s, 3, &read), "");
  s.saturated({true, false});
  EXPECT_NE(ReadState(s, 3, &read).find("saturated has 2 values"), std::string::npos);
  s.saturated({});
  // Enumerations are range-checked: a mode no driver sends is refused.
  s.mode(static_cast<msg::DriverMode>(7));
  EXPECT_NE(ReadState(s, 3, &read).find("mode 7"), std::string::npos);
}

TEST(ReadState, TheMotionMovesBetweenItsStartAndEndOnly) {
  msg::WaveplateState s;
  s.phi_applied({0.1, 0.2, 0.3});
  DriverState state;
  ASSERT_EQ(ReadState(s, 3, &state), "");  // no rate: φ holds
  const WaveplateMotion& motion = state.motion;
  EXPECT_FALSE(motion.moving);
  ControlVector phi;
  motion.At(123'456'789, &phi);
  EXPECT_EQ(phi, (ControlVector(3) << 0.1, 0.2, 0.3).finished());
  s.phi_rate_per_s({1.0, 0.0, -2.0});
  s.ramp_start_time_ns(1'000'000);
  s.ramp_end_time_ns(3'000'000);
  ASSERT_EQ(ReadState(s, 3, &state), "");
  EXPECT_TRUE(motion.moving);
  motion.At(0, &phi);
  EXPECT_NEAR(phi[0], 0.1, 1e-15);
  motion.At(2'000'000, &phi);
  EXPECT_NEAR(phi[0], 0.101, 1e-15);
  EXPECT_NEAR(phi[2], 0.298, 1e-15);
  motion.At(9'000'000, &phi);
  EXPECT_NEAR(phi[0], 0.102, 1e-15);
  EXPECT_NEAR(phi[2], 0.296, 1e-15);
  // An empty interval does not move, whatever the rate.
  s.ramp_end_time_ns(1'000'000);
  ASSERT_EQ(ReadState(s, 3, &state), "");
  EXPECT_FALSE(motion.moving);
}

TEST(WriteState, RoundTripsEveryField) {
  DriverState state;
  state.sequence = 1;
  state.answers_sample = 2;
  state.sample_time_ns = 3;
  state.sample_publish_time_ns = 4;
  state.command_receive_time_ns = 5;
  state.publish_time_ns = 6;
  state.motion = WaveplateMotion::Still((ControlVector(2) << 0.1, 0.2).finished());
  state.motion.rate_per_s = (ControlVector(2) << 1.0, -1.0).finished();
  state.motion.start_ns = 100;
  state.motion.end_ns = 200;
  state.motion.moving = true;
  state.saturated[1] = true;
  state.mode = DriverMode::kActive;
  state.reason = "obeying main";
  state.obeyed_controller_id = "main";
  state.obeyed_priority = 4;
  state.commands_applied = 7;
  state.commands_rejected = 8;
  state.commands_limited = 9;
  state.controller_switches = 10;
  state.last_rejection = "from x: y";
  msg::WaveplateState m;
  WriteState(state, "b", &m);
  EXPECT_EQ(m.saturated(), std::vector<bool>({false, true}));
  DriverState back;
  ASSERT_EQ(ReadState(m, 2, &back), "");
  EXPECT_EQ(back.sequence, 1u);
  EXPECT_EQ(back.answers_sample, 2u);
  EXPECT_EQ(back.sample_time_ns, 3);
  EXPECT_EQ(back.sample_publish_time_ns, 4);
  EXPECT_EQ(back.command_receive_time_ns, 5);
  EXPECT_EQ(back.publish_time_ns, 6);
  EXPECT_EQ(back.motion.phi, state.motion.phi);
  EXPECT_EQ(back.motion.rate_per_s, state.motion.rate_per_s);
  EXPECT_EQ(back.motion.start_ns, 100);
  EXPECT_EQ(back.motion.end_ns, 200);
  EXPECT_TRUE(back.motion.moving);
  EXPECT_TRUE(back.any_saturated());
  EXPECT_EQ(back.mode, DriverMode::kActive);
  EXPECT_EQ(back.reason, "obeying main");
  EXPECT_EQ(back.obeyed_controller_id, "main");
  EXPECT_EQ(back.obeyed_priority, 4);
  EXPECT_EQ(back.commands_applied, 7u);
  EXPECT_EQ(back.commands_rejected, 8u);
  EXPECT_EQ(back.commands_limited, 9u);
  EXPECT_EQ(back.controller_switches, 10u);
  EXPECT_EQ(back.last_rejection, "from x: y");
}

TEST(DeviceDescription, RoundTripsEveryStageKindMapAndRange) {
  std::vector<StageConfig> stages = StagesFromAxes("131");
  stages[0].range = ControlRange{-1.0, 1.0};
  stages[1].map.kind = ControlMapConfig::Kind::kPolynomial;
  stages[1].map.coefficients_rad = {0.1, 3.0, 0.2};
  StageConfig adjustable;
  adjustable.kind = StageConfig::Kind::kAdjustableAxis;
  adjustable.name = "qwp";
  adjustable.retardance.fixed_rad = M_PI / 2;
  adjustable.orientation.controlled = true;
  adjustable.orientation.range = ControlRange{-2.0, 2.0};
  stages.push_back(adjustable);
  DeviceDescription read;
  ASSERT_EQ(ReadDevice(DeviceMessage(DeviceDescription{"d", stages, 0.5, 2e-3}, "b"), &read), "");
  EXPECT_EQ(read.driver_id, "d");
  EXPECT_EQ(read.max_slew_per_s, 0.5);
  EXPECT_EQ(read.max_ramp_s, 2e-3);
  const std::vector<StageConfig>& back = read.stages;
  ASSERT_EQ(back.size(), stages.size());
  EXPECT_EQ(back[0].range->min, -1.0);
  EXPECT_EQ(back[1].map.kind, ControlMapConfig::Kind::kPolynomial);
  EXPECT_EQ(back[1].map.coefficients_rad, stages[1].map.coefficients_rad);
  EXPECT_EQ(back[2].axis, stages[2].axis);
  EXPECT_EQ(back[3].kind, StageConfig::Kind::kAdjustableAxis);
  EXPECT_TRUE(back[3].orientation.controlled);
  EXPECT_EQ(back[3].retardance.fixed_rad, M_PI / 2);
  EXPECT_EQ(back[3].name, "qwp");
}

TEST(DeviceDescription, TablesByConditionTravelAsTheTableAtTheOperatingPoint) {
  std::vector<StageConfig> stages = StagesFromAxes("131");
  stages[1].map.kind = ControlMapConfig::Kind::kTablesByCondition;
  stages[1].map.operating_point = 25.0;
  stages[1].map.condition_tables = {{20.0, {0, 1}, {0, 1}}, {30.0, {0, 1}, {0, 1.2}}};
  DeviceDescription read;
  ASSERT_EQ(ReadDevice(DeviceMessage(DeviceDescription{"d", stages, 0.0, 0.0}, "b"), &read), "");
  EXPECT_EQ(read.stages[1].map.kind, ControlMapConfig::Kind::kTable);
  EXPECT_EQ(read.stages[1].map.table_control, (std::vector<double>{0, 1}));
  ASSERT_EQ(read.stages[1].map.table_angle_rad.size(), 2u);
  EXPECT_NEAR(read.stages[1].map.table_angle_rad[1], 1.1, 1e-15);
}

TEST(DeviceDescription, ABadDescriptionIsRefusedWithTheFieldPath) {
  DeviceDescription read;
  msg::DeviceDescription d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.stages()[1].control_map().rad_per_unit(0.0);
  EXPECT_NE(ReadDevice(d, &read).find("stages[1]"), std::string::npos) << ReadDevice(d, &read);
  d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.stages()[2].kind(static_cast<msg::StageKind>(9));
  EXPECT_NE(ReadDevice(d, &read).find("device.stages[2].kind: unknown stage kind 9"), std::string::npos);
  d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.stages()[0].control_map().kind(static_cast<msg::ControlMapKind>(5));
  EXPECT_NE(ReadDevice(d, &read).find("unknown control map kind 5"), std::string::npos);
  d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.max_ramp_s(NAN);
  EXPECT_NE(ReadDevice(d, &read).find("max_ramp_s"), std::string::npos);
  d.max_ramp_s(0.0);
  d.stages().clear();
  EXPECT_NE(ReadDevice(d, &read), "");
}

TEST(TargetMessages, RoundTripAndValidation) {
  TargetConfig set;
  set.kind = TargetConfig::Kind::kSet;
  set.normal = Vector3(0, 0, 2);
  set.offset = 0.5;
  BenchTarget read;
  ASSERT_EQ(ReadTarget(TargetMessage(BenchTarget{3, "r1", set}, "b"), &read), "");
  EXPECT_EQ(read.revision, 3u);
  EXPECT_EQ(read.request_id, "r1");
  const TargetConfig& back = read.target;
  EXPECT_EQ(back.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(back.normal, set.normal);
  EXPECT_EQ(back.offset, 0.5);
  msg::Target bad = TargetMessage(BenchTarget{4, "", set}, "b");
  bad.kind(static_cast<msg::TargetKind>(2));
  EXPECT_NE(ReadTarget(bad, &read).find("unknown target kind 2"), std::string::npos);
  bad.kind(msg::TARGET_POINT);
  bad.point({0.0, 0.0, 2.0});
  EXPECT_NE(ReadTarget(bad, &read).find("target.point"), std::string::npos);
  EXPECT_EQ(read.revision, 3u) << "a refused target leaves what was read before";
  msg::TargetRequest request;
  request.kind(msg::TARGET_POINT);
  request.point({1.0, 1.0, 0.0});
  EXPECT_THROW(TargetFromRequest(request), ScenarioError);
  request.point({0.0, 0.0, 1.0});
  EXPECT_EQ(TargetFromRequest(request).point, StokesVector(0, 0, 1));
}

TEST(StatusMessage, CarriesEveryFieldCutToTheWireBounds) {
  ControllerStatusReport status;
  status.controller_id = "main";
  status.law = "gp";
  status.obeyed = true;
  status.condition = std::string(300, 'c');
  status.error_deg = 1.5;
  status.updates = 42;
  const msg::ControllerStatus m = StatusMessage(status, "b");
  EXPECT_EQ(m.bench_id().to_string(), "b");
  EXPECT_EQ(m.controller_id().to_string(), "main");
  EXPECT_EQ(m.law().to_string(), "gp");
  EXPECT_TRUE(m.obeyed());
  EXPECT_EQ(m.condition().size(), 127u);
  EXPECT_EQ(m.error_deg(), 1.5);
  EXPECT_EQ(m.updates(), 42u);
}

TEST(ReadStatus, RoundTripsWhatAControllerSends) {
  ControllerStatusReport status;
  status.controller_id = "main";
  status.priority = 10;
  status.law = "gp";
  status.obeyed = true;
  status.condition = "tracking";
  status.answers_sample = 77;
  status.error_deg = 1.5;
  status.sigma_max = 2.0;
  status.sigma_min = 0.5;
  status.nullspace_active_fraction = 0.25;
  status.compute_time_mean_s = 1e-6;
  status.compute_time_max_s = 3e-6;
  status.updates = 42;
  status.failed_updates = 1;
  status.rejected_samples = 2;
  status.missed_deadlines = 3;
  status.last_rejection = "a non-unit S_in";
  status.publish_time_ns = 99;
  ControllerStatusReport read;
  ASSERT_EQ(ReadStatus(StatusMessage(status, "b"), &read), "");
  EXPECT_EQ(read.controller_id, "main");
  EXPECT_EQ(read.priority, 10);
  EXPECT_EQ(read.law, "gp");
  EXPECT_TRUE(read.obeyed);
  EXPECT_EQ(read.condition, "tracking");
  EXPECT_EQ(read.answers_sample, 77u);
  EXPECT_EQ(read.sigma_min, 0.5);
  EXPECT_EQ(read.nullspace_active_fraction, 0.25);
  EXPECT_EQ(read.compute_time_max_s, 3e-6);
  EXPECT_EQ(read.failed_updates, 1u);
  EXPECT_EQ(read.rejected_samples, 2u);
  EXPECT_EQ(read.missed_deadlines, 3u);
  EXPECT_EQ(read.last_rejection, "a non-unit S_in");
  EXPECT_EQ(read.publish_time_ns, 99);
}

TEST(ReadStatus, RefusesFiguresNoControllerSendsAndCleansItsText) {
  ControllerStatusReport good;
  good.controller_id = "main";
  const auto refused = [&](auto change) {
    msg::ControllerStatus m = StatusMessage(good, "b");
    change(&m);
    ControllerStatusReport out;
    return ReadStatus(m, &out);
  };
  EXPECT_NE(refused([](msg::ControllerStatus* m) { m->error_deg(std::nan("")); }).find("error_deg"), std::string::npos);
  EXPECT_NE(refused([](msg::ControllerStatus* m) { m->error_deg(181.0); }).find("at most 180"), std::string::npos);
  EXPECT_NE(refused([](msg::ControllerStatus* m) { m->sigma_min(-1.0); }).find("sigma_min"), std::string::npos);
  EXPECT_NE(refused([](msg::ControllerStatus* m) { m->compute_time_max_s(INFINITY); }).find("compute_time_max_s"),
            std::string::npos);
  EXPECT_NE(refused([](msg::ControllerStatus* m) { m->nullspace_active_fraction(1.5); }).find("at most 1"),
            std::string::npos);
  EXPECT_EQ(refused([](msg::ControllerStatus* m) { m->controller_id(""); }), "no controller_id");
  msg::ControllerStatus m = StatusMessage(good, "b");
  m.condition("line\nbreak\x1b[2J");
  ControllerStatusReport out;
  ASSERT_EQ(ReadStatus(m, &out), "");
  EXPECT_EQ(out.condition, "line?break?[2J");
}

}  // namespace
}  // namespace dpc::bus

namespace dpc::bus {
namespace {

BenchSummary ASummary() {
  BenchSummary s;
  s.sequence = 7;
  s.publish_time_ns = 123;
  s.period_s = 0.05;
  s.samples = 500;
  s.last_sample = 3500;
  s.s_in = StokesVector(1.0, 0.0, 0.0);
  s.s_out = StokesVector(0.0, 0.6, 0.8);
  s.trail = {{1, 0, 0, 0, 0.6, 0.8}, {0, 1, 0, 0, 0, 1}};
  s.error_mean_deg = 1.25;
  s.error_max_deg = 2.5;
  s.latencies = 500;
  s.latency_p50_us = 210;
  s.latency_p90_us = 300;
  s.latency_p99_us = 800;
  s.latency_max_us = 1500;
  DriverState state;
  state.motion = WaveplateMotion::Still(ControlVector::Zero(3));
  state.motion.phi << 0.5, -0.25, 1.0;
  state.saturated[2] = true;
  state.mode = DriverMode::kHolding;
  state.reason = "no controller";
  state.controller_switches = 4;
  s.state = state;
  return s;
}

TEST(ReadSummary, RoundTripsWhatTheDashboardShows) {
  msg::BenchSummary message;
  WriteSummary(ASummary(), "bench1", &message);
  BenchSummary read;
  ASSERT_EQ(ReadSummary(message, &read), "");
  EXPECT_EQ(read.sequence, 7u);
  EXPECT_EQ(read.samples, 500u);
  EXPECT_EQ(read.trail.size(), 2u);
  EXPECT_DOUBLE_EQ(read.trail[1][5], 1.0);
  ASSERT_TRUE(read.error_mean_deg);
  EXPECT_DOUBLE_EQ(*read.error_mean_deg, 1.25);
  EXPECT_DOUBLE_EQ(read.latency_p99_us, 800);
  ASSERT_TRUE(read.state);
  EXPECT_EQ(read.state->control_count(), 3);
  EXPECT_DOUBLE_EQ(read.state->motion.phi[1], -0.25);
  EXPECT_TRUE(read.state->saturated[2]);
  EXPECT_EQ(read.state->mode, DriverMode::kHolding);
  EXPECT_EQ(read.state->reason, "no controller");
  EXPECT_EQ(read.state->controller_switches, 4u);

  BenchSummary empty;
  empty.sequence = 1;
  WriteSummary(empty, "bench1", &message);
  ASSERT_EQ(ReadSummary(message, &read), "");
  EXPECT_FALSE(read.error_mean_deg);
  EXPECT_FALSE(read.state);
  EXPECT_TRUE(read.trail.empty());
}

TEST(ReadSummary, NamesWhatIsWrong) {
  const auto problem = [](auto&& spoil) {
    msg::BenchSummary message;
    WriteSummary(ASummary(), "bench1", &message);
    spoil(message);
    BenchSummary read;
    return ReadSummary(message, &read);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(problem([&](auto& m) { m.error_mean_deg(nan); }).find("not finite"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.latency_p99_us(-1.0); }).find("negative"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.s_out({0.0, 2.0, 0.0}); }).find("s_out"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.trail().push_back(1.0); }).find("whole points"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.trail()[3] = 5.0; }).find("trail"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.saturated().pop_back(); }).find("saturated"), std::string::npos);
  EXPECT_NE(problem([&](auto& m) { m.phi_applied()[0] = nan; }).find("phi_applied"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.mode(static_cast<msg::DriverMode>(7)); }).find("mode 7"), std::string::npos);
  EXPECT_NE(problem([](auto& m) { m.sequence_number(0); }).find("sequence_number"), std::string::npos);
}

}  // namespace
}  // namespace dpc::bus
