#include "dpc/control/control_law_factory.h"

#include <gtest/gtest.h>

#include <climits>
#include <limits>

namespace dpc {
namespace {

TEST(ControlLawFactoryTest, MethodNamesRoundTrip) {
  for (const char* name :
       {"inverse", "transpose", "damped", "pinv", "rls", "gp", "gpt", "extended", "dither"}) {
    const auto method = ParseMethod(name);
    ASSERT_TRUE(method.has_value()) << name;
    EXPECT_EQ(MethodName(*method), name);
  }
  EXPECT_FALSE(ParseMethod("newton").has_value());
  EXPECT_EQ(MethodNameList(), "inverse|transpose|damped|pinv|rls|gp|gpt|extended|dither");
}

TEST(ControlLawFactoryTest, BuildsEveryMethodThatFits) {
  for (const char* name : {"transpose", "pinv", "rls", "gp", "gpt", "extended", "dither"}) {
    ControllerConfig config;
    config.method = *ParseMethod(name);
    const auto law = MakeControlLaw(config, LawTiming{}, 4, true);
    ASSERT_NE(law, nullptr);
    EXPECT_EQ(law->name(), name);
  }
  ControllerConfig inverse;
  inverse.method = ControlMethod::kInverse;
  EXPECT_EQ(MakeControlLaw(inverse, LawTiming{}, 3, true)->name(), "inverse");
  EXPECT_EQ(MakeControlLaw(inverse, LawTiming{}, 1, false)->name(), "inverse");
}

TEST(ControlLawFactoryTest, SquareMethodsNeedASquareTask) {
  for (ControlMethod method : {ControlMethod::kInverse, ControlMethod::kDamped}) {
    ControllerConfig config;
    config.method = method;
    EXPECT_THROW(MakeControlLaw(config, LawTiming{}, 4, true), std::invalid_argument);
    EXPECT_THROW(MakeControlLaw(config, LawTiming{}, 3, false), std::invalid_argument);
  }
}

TEST(ControlLawFactoryTest, PassesParametersThrough) {
  ControllerConfig config;
  config.method = ControlMethod::kRegularizedLeastSquares;
  config.damping = 0.0;
  EXPECT_THROW(MakeControlLaw(config, LawTiming{}, 4, true), std::invalid_argument);
  config.method = ControlMethod::kGradientProjection;
  config.step = -1.0;
  EXPECT_THROW(MakeControlLaw(config, LawTiming{}, 4, true), std::invalid_argument);
}

TEST(ControlLawFactoryTest, DitherSettleDefaultsToTheLoopDelay) {
  DitherConfig dither;
  ASSERT_EQ(dither.settle_samples, 0);
  EXPECT_EQ(BuildDitherSettings(dither, LawTiming{50e6, 50}).settle_samples, 50);
  dither.settle_samples = 7;
  EXPECT_EQ(BuildDitherSettings(dither, LawTiming{50e6, 50}).settle_samples, 7);
}

TEST(ControlLawFactoryTest, DitherResetSamplesAreRoundedAndAtLeastOne) {
  DitherConfig dither;
  dither.amplitude = 0.03;
  dither.reset_threshold = 0.9;
  dither.reset_duration_s = 2e-6;
  const DitherSettings settings = BuildDitherSettings(dither, LawTiming{50e6, 50});
  EXPECT_EQ(settings.reset_samples, 100);
  EXPECT_EQ(settings.amplitude, 0.03);
  EXPECT_EQ(settings.reset_threshold, 0.9);
  dither.reset_duration_s = 0.0;
  EXPECT_EQ(BuildDitherSettings(dither, LawTiming{50e6, 50}).reset_samples, 1);
  dither.reset_duration_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(BuildDitherSettings(dither, LawTiming{50e6, 50}).reset_samples, 1);
  dither.reset_duration_s = 1e300;
  EXPECT_EQ(BuildDitherSettings(dither, LawTiming{50e6, 50}).reset_samples, INT_MAX);
}

}  // namespace
}  // namespace dpc
