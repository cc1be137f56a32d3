#include "dpc/control/target.h"

#include <gtest/gtest.h>

#include <cmath>

namespace dpc {
namespace {

TEST(TargetTest, PointDistanceAndLeak) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  EXPECT_TRUE(target.is_point());
  EXPECT_NEAR(target.DistanceRad(StokesVector(0, 0.6, 0.8)), 0.0, 1e-15);
  EXPECT_NEAR(target.DistanceRad(StokesVector(0, -0.6, -0.8)), M_PI, 1e-15);
  // 1.15° off gives 40 dB extinction: sin²(α/2) = 1e-4 at α = 0.02 rad.
  const double alpha = 0.02;
  const StokesVector s(0, 0.6 * std::cos(alpha) - 0.8 * std::sin(alpha),
                       0.8 * std::cos(alpha) + 0.6 * std::sin(alpha));
  EXPECT_NEAR(target.DistanceRad(s), alpha, 1e-14);
  EXPECT_NEAR(target.LeakFraction(s), std::pow(std::sin(alpha / 2), 2), 1e-15);
  EXPECT_NEAR(10 * std::log10(target.LeakFraction(s)), -40.0, 0.01);
}

TEST(TargetTest, DistanceAndLeakAreAccurateForTinyAndHugeErrors) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  for (double alpha : {1e-12, 1e-8, 1e-4, 0.5, 1.5, 2.0, 3.0, M_PI - 1e-6}) {
    const StokesVector s(std::sin(alpha), 0.6 * std::cos(alpha), 0.8 * std::cos(alpha));
    double distance, leak;
    target.DistanceAndLeak(s, &distance, &leak);
    EXPECT_NEAR(distance, alpha, 2e-15 * std::max(1.0, alpha) + 1e-3 * alpha * 1e-12) << alpha;
    const double expected = std::pow(std::sin(alpha / 2), 2);
    EXPECT_NEAR(leak / expected, 1.0, 1e-9) << alpha;  // no cancellation at 1e-12 rad
  }
}

TEST(TargetTest, PointMustBeUnit) {
  EXPECT_THROW(Target::Point(StokesVector(0, 0.6, 0.9)), std::invalid_argument);
  EXPECT_THROW(Target::Point(StokesVector(NAN, 0, 1)), std::invalid_argument);
}

TEST(TargetTest, SetDistanceIsTheLatitudeDifference) {
  // s3 = 0: the equator ("any linear polarization").
  const Target equator = Target::Set(Vector3(0, 0, 2), 0.0);
  EXPECT_FALSE(equator.is_point());
  EXPECT_NEAR(equator.normal().norm(), 1.0, 1e-15);
  EXPECT_NEAR(equator.DistanceRad(StokesVector(1, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(equator.DistanceRad(StokesVector(0, 0, 1)), M_PI / 2, 1e-15);
  const double lat = 0.3;
  EXPECT_NEAR(equator.DistanceRad(StokesVector(std::cos(lat), 0, -std::sin(lat))), lat, 1e-15);
  EXPECT_NEAR(equator.LeakFraction(StokesVector(0, 0, 1)), 0.5, 1e-15);
  // The representative point lies on the set.
  EXPECT_NEAR(equator.normal().dot(equator.point()), 0.0, 1e-15);
}

TEST(TargetTest, SetOffsetIsNormalizedWithTheNormal) {
  const Target t = Target::Set(Vector3(0, 0, 2), 1.0);  // s3 = 0.5
  EXPECT_NEAR(t.offset(), 0.5, 1e-15);
  EXPECT_NEAR(t.normal().dot(t.point()), 0.5, 1e-15);
  EXPECT_NEAR(t.point().norm(), 1.0, 1e-15);
}

TEST(TargetTest, SetRejectsDegenerateSets) {
  EXPECT_THROW(Target::Set(Vector3::Zero(), 0.0), std::invalid_argument);
  EXPECT_THROW(Target::Set(Vector3::UnitZ(), 1.0), std::invalid_argument);
  EXPECT_THROW(Target::Set(Vector3::UnitZ(), -1.5), std::invalid_argument);
  EXPECT_THROW(Target::Set(Vector3::UnitZ(), NAN), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
