#include "dpc/disturbance/constant_rotation_disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

class ConstantRotationDisturbanceTest : public ::testing::Test {
 protected:
  static constexpr double kSampleRateHz = 50e6;
  RandomSource random_{1, 1};
};

TEST_F(ConstantRotationDisturbanceTest, ExactAngleAfterNSamplesAboutS3) {
  ConstantRotationDisturbance rotation(1e5, Vector3::UnitZ(), kSampleRateHz);
  StokesVector sop = StokesVector::UnitX();
  constexpr int kSamples = 5000;
  for (int k = 0; k < kSamples; ++k) rotation.Advance(k / kSampleRateHz, &sop, random_);
  const double angle_rad = 1e5 / kSampleRateHz * kSamples;  // 10 rad
  EXPECT_LT((sop - StokesVector(std::cos(angle_rad), std::sin(angle_rad), 0.0)).norm(), 1e-12);
}

TEST_F(ConstantRotationDisturbanceTest, ExactAngleAboutAnArbitraryAxis) {
  const Vector3 axis = Vector3(1.0, -2.0, 3.0);
  ConstantRotationDisturbance rotation(3e5, axis, kSampleRateHz);
  EXPECT_LT((rotation.axis() - axis.normalized()).norm(), 1e-15);
  const StokesVector initial = StokesVector(0.0, 0.6, 0.8);
  StokesVector sop = initial;
  constexpr int kSamples = 2000;
  for (int k = 0; k < kSamples; ++k) rotation.Advance(k / kSampleRateHz, &sop, random_);
  const StokesVector expected =
      RotationAboutAxis(axis.normalized(), 3e5 / kSampleRateHz * kSamples) * initial;
  EXPECT_LT((sop - expected).norm(), 1e-12);
}

TEST_F(ConstantRotationDisturbanceTest, TheAxisIsFixedAndNothingIsDrawn) {
  const Vector3 axis = Vector3(0.0, 0.6, 0.8);
  ConstantRotationDisturbance rotation(1e6, axis, kSampleRateHz);
  StokesVector sop = axis;
  for (int k = 0; k < 1000; ++k) rotation.Advance(k / kSampleRateHz, &sop, random_);
  EXPECT_LT((sop - axis).norm(), 1e-13);
  RandomSource fresh(1, 1);
  EXPECT_EQ(random_.Uniform(), fresh.Uniform());
}

TEST_F(ConstantRotationDisturbanceTest, ZeroRateHoldsTheSop) {
  ConstantRotationDisturbance rotation(0.0, Vector3::UnitX(), kSampleRateHz);
  StokesVector sop(0.0, 0.6, 0.8);
  rotation.Advance(0.0, &sop, random_);
  EXPECT_EQ(sop, StokesVector(0.0, 0.6, 0.8));
}

TEST_F(ConstantRotationDisturbanceTest, DescribeNamesRateAndAxis) {
  EXPECT_EQ(ConstantRotationDisturbance(1e5, Vector3::UnitZ(), kSampleRateHz).Describe(),
            "constant rotation: 100000 rad/s about [0, 0, 1]");
}

TEST_F(ConstantRotationDisturbanceTest, RejectsNegativeRate) {
  EXPECT_THROW(ConstantRotationDisturbance(-1.0, Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(ConstantRotationDisturbanceTest, RejectsNonFiniteRate) {
  EXPECT_THROW(ConstantRotationDisturbance(INFINITY, Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(ConstantRotationDisturbanceTest, RejectsZeroAxis) {
  EXPECT_THROW(ConstantRotationDisturbance(1.0, Vector3::Zero(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(ConstantRotationDisturbanceTest, RejectsBadSampleRate) {
  EXPECT_THROW(ConstantRotationDisturbance(1.0, Vector3::UnitZ(), NAN), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
