#include "dpc/disturbance/disturbance_factory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dpc/disturbance/constant_rotation_disturbance.h"
#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/disturbance/random_walk_disturbance.h"
#include "dpc/disturbance/transient_burst_disturbance.h"

namespace dpc {
namespace {

using Kind = DisturbanceConfig::Kind;

class DisturbanceFactoryTest : public ::testing::Test {
 protected:
  static constexpr double kSampleRateHz = 50e6;

  static DisturbanceConfig Config(Kind kind) {
    DisturbanceConfig config;
    config.kind = kind;
    return config;
  }
};

TEST_F(DisturbanceFactoryTest, DefaultConfigIsThePaperScrambler) {
  const std::unique_ptr<Disturbance> disturbance =
      MakeDisturbance(DisturbanceConfig{}, kSampleRateHz);
  const auto* scrambler = dynamic_cast<const PaperScrambler*>(disturbance.get());
  ASSERT_NE(scrambler, nullptr);
  EXPECT_DOUBLE_EQ(scrambler->rate_rad_per_s(), 1e5);
  EXPECT_DOUBLE_EQ(scrambler->kick_sigma_rad(), 1e5 / kSampleRateHz);
  EXPECT_EQ(scrambler->rotation_axis(), Vector3::UnitZ());
  EXPECT_EQ(scrambler->kick_axis(), Vector3::UnitY());
}

TEST_F(DisturbanceFactoryTest, BuildsARandomWalk) {
  DisturbanceConfig config = Config(Kind::kRandomWalk);
  config.diffusion_rad_per_sqrt_s = 20.0;
  const std::unique_ptr<Disturbance> disturbance = MakeDisturbance(config, kSampleRateHz);
  const auto* walk = dynamic_cast<const RandomWalkDisturbance*>(disturbance.get());
  ASSERT_NE(walk, nullptr);
  EXPECT_DOUBLE_EQ(walk->diffusion_rad_per_sqrt_s(), 20.0);
}

TEST_F(DisturbanceFactoryTest, BuildsAConstantRotation) {
  DisturbanceConfig config = Config(Kind::kConstantRotation);
  config.rate_rad_per_s = 3e4;
  config.axis = Vector3(0.0, 0.0, -2.0);
  const std::unique_ptr<Disturbance> disturbance = MakeDisturbance(config, kSampleRateHz);
  const auto* rotation = dynamic_cast<const ConstantRotationDisturbance*>(disturbance.get());
  ASSERT_NE(rotation, nullptr);
  EXPECT_DOUBLE_EQ(rotation->rate_rad_per_s(), 3e4);
  EXPECT_EQ(rotation->axis(), -Vector3::UnitZ());
}

TEST_F(DisturbanceFactoryTest, BuildsATransientBurstWithAFixedAxis) {
  DisturbanceConfig config = Config(Kind::kTransientBurst);
  config.rate_rad_per_s = 5e6;
  config.start_s = 1e-3;
  config.duration_s = 1e-4;
  config.period_s = 2e-3;
  config.envelope = DisturbanceConfig::Envelope::kRectangular;
  config.axis = Vector3::UnitX();
  const std::unique_ptr<Disturbance> disturbance = MakeDisturbance(config, kSampleRateHz);
  const auto* burst = dynamic_cast<const TransientBurstDisturbance*>(disturbance.get());
  ASSERT_NE(burst, nullptr);
  EXPECT_DOUBLE_EQ(burst->peak_rate_rad_per_s(), 5e6);
  EXPECT_DOUBLE_EQ(burst->start_s(), 1e-3);
  EXPECT_DOUBLE_EQ(burst->duration_s(), 1e-4);
  EXPECT_DOUBLE_EQ(burst->period_s(), 2e-3);
  EXPECT_EQ(burst->envelope(), DisturbanceConfig::Envelope::kRectangular);
  EXPECT_FALSE(burst->random_axis());
  EXPECT_EQ(burst->current_axis(), Vector3::UnitX());
}

TEST_F(DisturbanceFactoryTest, BuildsATransientBurstWithRandomAxes) {
  DisturbanceConfig config = Config(Kind::kTransientBurst);
  config.duration_s = 1e-4;
  config.random_axis = true;
  const std::unique_ptr<Disturbance> disturbance = MakeDisturbance(config, kSampleRateHz);
  const auto* burst = dynamic_cast<const TransientBurstDisturbance*>(disturbance.get());
  ASSERT_NE(burst, nullptr);
  EXPECT_TRUE(burst->random_axis());
  EXPECT_EQ(burst->envelope(), DisturbanceConfig::Envelope::kHalfSine);
}

TEST_F(DisturbanceFactoryTest, RejectsANegativeScramblerRate) {
  DisturbanceConfig config;
  config.rate_rad_per_s = -1.0;
  EXPECT_THROW(MakeDisturbance(config, kSampleRateHz), std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, RejectsAZeroKickAxis) {
  DisturbanceConfig config;
  config.kick_axis = Vector3::Zero();
  EXPECT_THROW(MakeDisturbance(config, kSampleRateHz), std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, RejectsANegativeDiffusion) {
  DisturbanceConfig config = Config(Kind::kRandomWalk);
  config.diffusion_rad_per_sqrt_s = -1.0;
  EXPECT_THROW(MakeDisturbance(config, kSampleRateHz), std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, RejectsAZeroRotationAxis) {
  DisturbanceConfig config = Config(Kind::kConstantRotation);
  config.axis = Vector3::Zero();
  EXPECT_THROW(MakeDisturbance(config, kSampleRateHz), std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, RejectsABurstWithoutDuration) {
  // The default duration_s is 0: a burst must say how long it lasts.
  EXPECT_THROW(MakeDisturbance(Config(Kind::kTransientBurst), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, IgnoresTheAxisOfARandomAxisBurst) {
  DisturbanceConfig config = Config(Kind::kTransientBurst);
  config.duration_s = 1e-4;
  config.random_axis = true;
  config.axis = Vector3::Zero();
  EXPECT_NO_THROW(MakeDisturbance(config, kSampleRateHz));
}

TEST_F(DisturbanceFactoryTest, RejectsAnUnknownKind) {
  EXPECT_THROW(MakeDisturbance(Config(static_cast<Kind>(99)), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(DisturbanceFactoryTest, RejectsABadSampleRate) {
  EXPECT_THROW(MakeDisturbance(DisturbanceConfig{}, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
