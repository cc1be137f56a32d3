#include "dpc/control/control_law_factory.h"

#include <gtest/gtest.h>

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
    ControlLawConfig config;
    config.method = *ParseMethod(name);
    const auto law = MakeControlLaw(config, 4, true);
    ASSERT_NE(law, nullptr);
    EXPECT_EQ(law->name(), name);
  }
  ControlLawConfig inverse;
  inverse.method = ControlMethod::kInverse;
  EXPECT_EQ(MakeControlLaw(inverse, 3, true)->name(), "inverse");
  EXPECT_EQ(MakeControlLaw(inverse, 1, false)->name(), "inverse");
}

TEST(ControlLawFactoryTest, SquareMethodsNeedASquareTask) {
  for (ControlMethod method : {ControlMethod::kInverse, ControlMethod::kDamped}) {
    ControlLawConfig config;
    config.method = method;
    EXPECT_THROW(MakeControlLaw(config, 4, true), std::invalid_argument);
    EXPECT_THROW(MakeControlLaw(config, 3, false), std::invalid_argument);
  }
}

TEST(ControlLawFactoryTest, PassesParametersThrough) {
  ControlLawConfig config;
  config.method = ControlMethod::kRegularizedLeastSquares;
  config.damping = 0.0;
  EXPECT_THROW(MakeControlLaw(config, 4, true), std::invalid_argument);
  config.method = ControlMethod::kGradientProjection;
  config.step = -1.0;
  EXPECT_THROW(MakeControlLaw(config, 4, true), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
