#include "dpc/optics/waveplate_stage.h"

#include <gtest/gtest.h>

#include <cmath>

#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

TEST(WaveplateStageTest, FixedAxisNormalizesTheAxis) {
  const WaveplateStage stage = WaveplateStage::FixedAxis(Vector3(0, 3, 4));
  EXPECT_LT((stage.axis() - Vector3(0, 0.6, 0.8)).norm(), 1e-15);
  EXPECT_EQ(stage.controls().size(), 1u);
  EXPECT_EQ(stage.Describe(), "R[0,0.6,0.8]");
}

TEST(WaveplateStageTest, FixedAxisRejectsZeroAndNonFiniteAxes) {
  EXPECT_THROW(WaveplateStage::FixedAxis(Vector3::Zero()), std::invalid_argument);
  EXPECT_THROW(WaveplateStage::FixedAxis(Vector3(NAN, 0, 1)), std::invalid_argument);
}

TEST(WaveplateStageTest, RejectsEmptyAndNonFiniteRanges) {
  EXPECT_THROW(WaveplateStage::FixedAxis(Vector3::UnitX(), ControlMap::Linear(),
                                         ControlRange{1.0, 1.0}),
               std::invalid_argument);
  EXPECT_THROW(WaveplateStage::FixedAxis(Vector3::UnitX(), ControlMap::Linear(),
                                         ControlRange{-INFINITY, 1.0}),
               std::invalid_argument);
}

TEST(WaveplateStageTest, FixedAxisMuellerMatrixIsTheRotationByTheMappedAngle) {
  const WaveplateStage stage =
      WaveplateStage::FixedAxis(Vector3::UnitZ(), ControlMap::Linear(2.0, 0.1));
  EXPECT_LT((stage.MuellerMatrix({0.4}) - R3(0.9)).norm(), 1e-15);
  EXPECT_THROW(stage.MuellerMatrix({0.4, 0.1}), std::invalid_argument);
}

TEST(WaveplateStageTest, AdjustableAxisIsR3R1R3Transpose) {
  const WaveplateStage stage = WaveplateStage::AdjustableAxis(
      StageAngle::Controlled(ControlMap::Linear()), StageAngle::Controlled(ControlMap::Linear(2.0)));
  ASSERT_EQ(stage.controls().size(), 2u);
  const double theta = M_PI * 0.3, phi = 2.0 * -0.7;
  const Matrix3 expected = R3(phi) * R1(theta) * R3(phi).transpose();
  EXPECT_LT((stage.MuellerMatrix({0.3, -0.7}) - expected).norm(), 1e-15);
  // The same as a rotation by θ about [cos ϕ, sin ϕ, 0].
  EXPECT_LT((expected - RotationAboutAxis(Vector3(std::cos(phi), std::sin(phi), 0), theta)).norm(),
            1e-14);
}

TEST(WaveplateStageTest, RotatableQuarterWavePlateHasOneControl) {
  const WaveplateStage stage = WaveplateStage::AdjustableAxis(
      StageAngle::Fixed(M_PI / 2), StageAngle::Controlled(ControlMap::Linear()));
  ASSERT_EQ(stage.controls().size(), 1u);
  const Matrix3 expected = R3(M_PI * 0.25) * R1(M_PI / 2) * R3(M_PI * 0.25).transpose();
  EXPECT_LT((stage.MuellerMatrix({0.25}) - expected).norm(), 1e-15);
}

TEST(WaveplateStageTest, AdjustableAxisNeedsAControl) {
  EXPECT_THROW(WaveplateStage::AdjustableAxis(StageAngle::Fixed(1.0), StageAngle::Fixed(0.0)),
               std::invalid_argument);
  EXPECT_THROW(WaveplateStage::AdjustableAxis(StageAngle::Fixed(NAN),
                                              StageAngle::Controlled(ControlMap::Linear())),
               std::invalid_argument);
}

TEST(WaveplateStageTest, DescribeNamesElementalAxes) {
  EXPECT_EQ(WaveplateStage::FixedAxis(Vector3::UnitX()).Describe(), "R1");
  EXPECT_EQ(WaveplateStage::FixedAxis(Vector3::UnitY()).Describe(), "R2");
  EXPECT_EQ(WaveplateStage::FixedAxis(Vector3::UnitZ()).Describe(), "R3");
}

TEST(ControlRangeTest, ClampAndContains) {
  const ControlRange range{-1.0, 2.0};
  EXPECT_TRUE(range.Contains(2.0));
  EXPECT_FALSE(range.Contains(2.5));
  EXPECT_EQ(range.Clamp(-3.0), -1.0);
  EXPECT_EQ(range.Clamp(0.5), 0.5);
}

}  // namespace
}  // namespace dpc
