#include "dpc/disturbance/disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

TEST(DisturbanceChecksTest, SamplePeriodIsTheReciprocalRate) {
  EXPECT_DOUBLE_EQ(SamplePeriodFromRate(50e6, "test"), 2e-8);
}

TEST(DisturbanceChecksTest, SamplePeriodRejectsBadRates) {
  EXPECT_THROW(SamplePeriodFromRate(0.0, "test"), std::invalid_argument);
  EXPECT_THROW(SamplePeriodFromRate(-1.0, "test"), std::invalid_argument);
  EXPECT_THROW(SamplePeriodFromRate(INFINITY, "test"), std::invalid_argument);
  EXPECT_THROW(SamplePeriodFromRate(NAN, "test"), std::invalid_argument);
}

TEST(DisturbanceChecksTest, NormalizedAxisHasUnitLength) {
  EXPECT_LT((NormalizedAxis(Vector3(0, 3, 4), "axis") - Vector3(0, 0.6, 0.8)).norm(), 1e-15);
}

TEST(DisturbanceChecksTest, NormalizedAxisRejectsZeroAndNonFiniteAxes) {
  EXPECT_THROW(NormalizedAxis(Vector3::Zero(), "axis"), std::invalid_argument);
  EXPECT_THROW(NormalizedAxis(Vector3(NAN, 0, 1), "axis"), std::invalid_argument);
  EXPECT_THROW(NormalizedAxis(Vector3(INFINITY, 0, 1), "axis"), std::invalid_argument);
}

TEST(DisturbanceChecksTest, NonNegativeFinite) {
  EXPECT_NO_THROW(RequireNonNegativeFinite(0.0, "x"));
  EXPECT_NO_THROW(RequireNonNegativeFinite(5e6, "x"));
  EXPECT_THROW(RequireNonNegativeFinite(-1e-300, "x"), std::invalid_argument);
  EXPECT_THROW(RequireNonNegativeFinite(NAN, "x"), std::invalid_argument);
  EXPECT_THROW(RequireNonNegativeFinite(INFINITY, "x"), std::invalid_argument);
}

TEST(DisturbanceChecksTest, MessagesNameTheField) {
  try {
    RequireNonNegativeFinite(-2.0, "paper scrambler: rate_rad_per_s");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("rate_rad_per_s"), std::string::npos);
  }
}

}  // namespace
}  // namespace dpc
