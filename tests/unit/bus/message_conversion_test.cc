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

TEST(CheckCommandShape, NamesTheProblem) {
  msg::WaveplateCommand c;
  c.controller_id("A");
  c.phi({0.1, 0.2, 0.3});
  EXPECT_EQ(CheckCommandShape(c, 3), "");
  EXPECT_NE(CheckCommandShape(c, 4).find("the device has 4 controls"), std::string::npos);
  c.phi(std::vector<double>(17, 0.0));
  EXPECT_NE(CheckCommandShape(c, 3).find("oversized"), std::string::npos);
  c.phi({0.1, NAN, 0.3});
  EXPECT_NE(CheckCommandShape(c, 3).find("phi[1]"), std::string::npos);
  c.phi({0.1, 0.2, 0.3});
  c.controller_id("");
  EXPECT_NE(CheckCommandShape(c, 3).find("controller_id"), std::string::npos);
  c.controller_id("A");
  c.phi_rate_per_s({1.0, 2.0, 3.0});
  EXPECT_EQ(CheckCommandShape(c, 3), "");
  c.phi_rate_per_s({1.0, 2.0});
  EXPECT_NE(CheckCommandShape(c, 3).find("phi_rate_per_s has 2 values"), std::string::npos);
  c.phi_rate_per_s({1.0, INFINITY, 3.0});
  EXPECT_NE(CheckCommandShape(c, 3).find("phi_rate_per_s[1]"), std::string::npos);
}

TEST(CheckStateShape, NamesTheProblem) {
  msg::WaveplateState s;
  s.phi_applied({0.1, 0.2, 0.3});
  EXPECT_EQ(CheckStateShape(s, 3), "");
  EXPECT_NE(CheckStateShape(s, 2).find("phi_applied has 3 values"), std::string::npos);
  s.phi_applied({0.1, NAN, 0.3});
  EXPECT_NE(CheckStateShape(s, 3).find("phi_applied[1]"), std::string::npos);
  s.phi_applied({0.1, 0.2, 0.3});
  s.phi_rate_per_s({1.0});
  EXPECT_NE(CheckStateShape(s, 3).find("phi_rate_per_s has 1 values"), std::string::npos);
  s.phi_rate_per_s({1.0, 0.0, NAN});
  EXPECT_NE(CheckStateShape(s, 3).find("phi_rate_per_s[2]"), std::string::npos);
  s.phi_rate_per_s({1.0, 0.0, -2.0});
  s.ramp_start_time_ns(5'000'000);
  s.ramp_end_time_ns(4'000'000);
  EXPECT_NE(CheckStateShape(s, 3).find("ramp_end_time_ns"), std::string::npos);
  // A ramp across the whole int64 range would overflow t − start in every reader.
  s.ramp_start_time_ns(std::numeric_limits<int64_t>::min());
  s.ramp_end_time_ns(std::numeric_limits<int64_t>::max());
  EXPECT_NE(CheckStateShape(s, 3).find("longer than any driver ramps"), std::string::npos);
  s.ramp_start_time_ns(0);
  s.ramp_end_time_ns(1'000'000'000);
  EXPECT_EQ(CheckStateShape(s, 3), "");
  // Enumerations are range-checked: a mode no driver sends is refused.
  s.mode(static_cast<msg::DriverMode>(7));
  EXPECT_NE(CheckStateShape(s, 3).find("mode 7"), std::string::npos);
}

TEST(AppliedTrajectory, MovesBetweenItsStartAndEndOnly) {
  msg::WaveplateState s;
  s.phi_applied({0.1, 0.2, 0.3});
  AppliedTrajectory motion;
  ReadTrajectory(s, &motion);  // no rate: φ holds
  EXPECT_FALSE(motion.moving);
  ControlVector phi;
  motion.At(123'456'789, &phi);
  EXPECT_EQ(phi, (ControlVector(3) << 0.1, 0.2, 0.3).finished());
  s.phi_rate_per_s({1.0, 0.0, -2.0});
  s.ramp_start_time_ns(1'000'000);
  s.ramp_end_time_ns(3'000'000);
  ReadTrajectory(s, &motion);
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
  ReadTrajectory(s, &motion);
  EXPECT_FALSE(motion.moving);
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
  const std::vector<StageConfig> back = StagesFromDescription(DescribeDevice(stages, "b", "d", 0.5));
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

TEST(DeviceDescription, ABadDescriptionIsRefusedWithTheFieldPath) {
  msg::DeviceDescription d = DescribeDevice(StagesFromAxes("131"), "b", "d", 0.0);
  d.stages()[1].control_map().rad_per_unit(0.0);
  try {
    StagesFromDescription(d);
    FAIL() << "accepted a zero map";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("stages[1]"), std::string::npos) << e.what();
  }
  d = DescribeDevice(StagesFromAxes("131"), "b", "d", 0.0);
  d.stages().clear();
  EXPECT_THROW(StagesFromDescription(d), ScenarioError);
}

TEST(TargetMessages, RoundTripAndValidation) {
  TargetConfig set;
  set.kind = TargetConfig::Kind::kSet;
  set.normal = Vector3(0, 0, 2);
  set.offset = 0.5;
  const TargetConfig back = TargetFromMessage(TargetMessage(set, "b", 3, "r1"));
  EXPECT_EQ(back.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(back.normal, set.normal);
  EXPECT_EQ(back.offset, 0.5);
  msg::TargetRequest request;
  request.kind(msg::TARGET_POINT);
  request.point({1.0, 1.0, 0.0});
  EXPECT_THROW(TargetFromRequest(request), ScenarioError);
  request.point({0.0, 0.0, 1.0});
  EXPECT_EQ(TargetFromRequest(request).point, StokesVector(0, 0, 1));
}

}  // namespace
}  // namespace dpc::bus
