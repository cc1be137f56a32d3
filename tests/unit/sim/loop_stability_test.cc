#include "dpc/sim/loop_stability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

namespace dpc {
namespace {

// Largest root modulus of z^D − z^(D−1) + μ by iterating the recurrence y[k] = y[k−1] − μ y[k−D]
// and measuring the growth rate (simple and independent of the closed form).
double GrowthRate(int delay, double mu) {
  std::vector<double> y(delay, 1.0);
  double norm_before = 0.0;
  const int steps = 20000;
  for (int k = 0; k < steps; ++k) {
    const double next = y.back() - mu * y[y.size() - delay];
    y.push_back(next);
    if (k == steps / 2) norm_before = std::abs(next) + std::abs(y[y.size() - 2]);
  }
  const double norm_after = std::abs(y.back()) + std::abs(y[y.size() - 2]);
  return std::pow(norm_after / norm_before, 1.0 / (steps / 2));
}

TEST(LoopStabilityTest, KnownValues) {
  EXPECT_NEAR(MeasuredLoopStepLimit(1), 2.0, 1e-15);
  EXPECT_NEAR(MeasuredLoopStepLimit(2), 1.0, 1e-15);
  EXPECT_NEAR(MeasuredLoopStepLimit(50), 2 * std::sin(M_PI / 198), 1e-15);
  EXPECT_NEAR(MeasuredLoopStepLimit(50), 0.03173, 1e-5);
  EXPECT_THROW(MeasuredLoopStepLimit(0), std::invalid_argument);
}

TEST(LoopStabilityTest, LimitSeparatesDecayFromGrowth) {
  for (int delay : {1, 2, 3, 5, 10, 50}) {
    const double limit = MeasuredLoopStepLimit(delay);
    EXPECT_LT(GrowthRate(delay, 0.97 * limit), 1.0) << delay;
    EXPECT_GT(GrowthRate(delay, 1.03 * limit), 1.0) << delay;
  }
}

TEST(LoopStabilityTest, WarnsAboutAnUnstableMeasuredLoop) {
  ScenarioConfig s = PaperScenario("131");
  EXPECT_TRUE(ScenarioWarnings(s).empty());
  s.controller.loop = LoopMode::kMeasured;  // step 0.1 > 0.0317
  const auto warnings = ScenarioWarnings(s);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("0.0317"), std::string::npos) << warnings[0];
  s.controller.step = 0.02;
  EXPECT_TRUE(ScenarioWarnings(s).empty());
}

TEST(LoopStabilityTest, WarnsThatInverseNeverActs) {
  ScenarioConfig s = PaperScenario("131");
  s.controller.method = ControlMethod::kInverse;
  EXPECT_EQ(ScenarioWarnings(s).size(), 1u);
}

}  // namespace
}  // namespace dpc
