#include "dpc/sim/loop_stability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

namespace dpc {
namespace {

// Growth per sample of y[k] = y[k−1] − μ·y[k−D] (characteristic z^D − z^(D−1) + μ), measured
// from the largest |y| over two windows once transients have died out: independent of the
// closed form. The state is rescaled when it gets large, so no overflow.
double GrowthRate(int delay, double mu) {
  std::vector<double> y(delay, 1.0);
  double log_scale = 0.0, peak_early = -INFINITY, peak_late = -INFINITY;
  const int steps = 40 * (delay + 10) * 8;
  for (int k = 0; k < steps; ++k) {
    const double next = y.back() - mu * y[y.size() - delay];
    y.push_back(next);
    double window_max = 0.0;
    for (size_t i = y.size() - delay; i < y.size(); ++i) window_max = std::max(window_max, std::abs(y[i]));
    if (window_max > 1e100 || (window_max < 1e-100 && window_max > 0.0)) {
      const double factor = 1.0 / window_max;
      for (double& v : y) v *= factor;
      log_scale += std::log(window_max);
    }
    const double magnitude = std::log(std::abs(y.back()) + 1e-300) + log_scale;
    if (k >= steps / 2 && k < 3 * steps / 4) peak_early = std::max(peak_early, magnitude);
    if (k >= 3 * steps / 4) peak_late = std::max(peak_late, magnitude);
  }
  return std::exp((peak_late - peak_early) / (steps / 4));
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
