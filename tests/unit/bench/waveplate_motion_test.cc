#include "dpc/bench/waveplate_motion.h"

#include <gtest/gtest.h>

#include <limits>

namespace dpc {
namespace {

WaveplateMotion Ramp() {
  WaveplateMotion motion = WaveplateMotion::Still((ControlVector(2) << 0.1, 0.2).finished());
  motion.rate_per_s = (ControlVector(2) << 10.0, -20.0).finished();
  motion.start_ns = 1'000'000;
  motion.end_ns = 3'000'000;
  motion.moving = true;
  return motion;
}

TEST(WaveplateMotionTest, AStillMotionHoldsItsPointAtAnyTime) {
  const WaveplateMotion still = WaveplateMotion::Still((ControlVector(2) << 0.1, 0.2).finished());
  EXPECT_FALSE(still.moving);
  EXPECT_EQ(still.rate_per_s, ControlVector::Zero(2));
  ControlVector phi;
  for (int64_t t : {std::numeric_limits<int64_t>::min(), int64_t{0}, std::numeric_limits<int64_t>::max()}) {
    still.At(t, &phi);
    EXPECT_EQ(phi, still.phi) << t;
  }
}

TEST(WaveplateMotionTest, ARampMovesBetweenItsStartAndEndOnly) {
  const WaveplateMotion ramp = Ramp();
  ControlVector phi;
  ramp.At(0, &phi);
  EXPECT_EQ(phi, ramp.phi);
  ramp.At(2'000'000, &phi);
  EXPECT_NEAR(phi[0], 0.11, 1e-15);
  EXPECT_NEAR(phi[1], 0.18, 1e-15);
  ramp.At(std::numeric_limits<int64_t>::max(), &phi);
  EXPECT_NEAR(phi[0], 0.12, 1e-15);
  EXPECT_NEAR(phi[1], 0.16, 1e-15);
}

TEST(WaveplateMotionTest, StoppedHoldsWhereTheRampEnds) {
  const WaveplateMotion stopped = Ramp().Stopped();
  EXPECT_FALSE(stopped.moving);
  EXPECT_EQ(stopped.start_ns, 3'000'000);
  EXPECT_NEAR(stopped.phi[0], 0.12, 1e-15);
  EXPECT_NEAR(stopped.phi[1], 0.16, 1e-15);
  EXPECT_EQ(stopped.rate_per_s, ControlVector::Zero(2));
}

}  // namespace
}  // namespace dpc
