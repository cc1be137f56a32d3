#include <gtest/gtest.h>

#include <tuple>
#include <vector>

#include "dpc/control/control_law_factory.h"
#include "dpc/sim/closed_loop_simulator.h"

namespace dpc {
namespace {

class Recorder : public SimulationObserver {
 public:
  void OnSample(const SampleView& s) override {
    s_out.push_back(s.s_out);
    phi.push_back(s.phi_applied);
  }
  std::vector<StokesVector> s_out;
  std::vector<ControlVector> phi;
};

// The general loop on the same scenario: a user-supplied law factory (here the built-in one)
// keeps the simulator off the fast path.
ClosedLoopSimulator General(const ScenarioConfig& s) {
  return ClosedLoopSimulator(s, [](const ControllerConfig& c, const LawTiming& timing, int n, bool point) {
    return MakeControlLaw(c, timing, n, point);
  });
}

ScenarioConfig Short(const char* axes) {
  ScenarioConfig s = PaperScenario(axes);
  s.simulation.duration_s = 1e-3;
  s.controller.activation_s = 0.1e-3;
  s.simulation.settle_samples = 100;
  s.input.disturbances[0].rate_rad_per_s = 3e4;
  return s;
}

using Case = std::tuple<const char*, ControlMethod, LoopMode, double /*noise_deg*/,
                        double /*delay_s*/>;

class FastPathTest : public ::testing::TestWithParam<Case> {};

TEST_P(FastPathTest, FollowsTheGeneralLoop) {
  const auto [axes, method, loop, noise_deg, delay_s] = GetParam();
  ScenarioConfig s = Short(axes);
  s.controller.method = method;
  s.controller.loop = loop;
  s.controller.step = loop == LoopMode::kMeasured ? 0.02 : 0.1;
  s.controller.threshold = 0.3;  // gpt switches its null-space term on and off
  s.simulation.polarimeter_noise_deg = noise_deg;
  s.simulation.delay_s = delay_s;
  ClosedLoopSimulator fast(s);
  ClosedLoopSimulator general = General(s);
  ASSERT_TRUE(fast.uses_fast_path());
  ASSERT_FALSE(general.uses_fast_path());
  Recorder a, b;
  const SimulationResult ra = fast.Run(&a, 1);
  const SimulationResult rb = general.Run(&b, 1);
  ASSERT_EQ(a.s_out.size(), b.s_out.size());
  double worst = 0.0;
  for (size_t k = 0; k < a.s_out.size(); ++k) {
    worst = std::max(worst, (a.s_out[k] - b.s_out[k]).norm());
    worst = std::max(worst, (a.phi[k] - b.phi[k]).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-10);
  const RunSummary& x = ra.summary;
  const RunSummary& y = rb.summary;
  EXPECT_NEAR(x.error_deg.mean, y.error_deg.mean, 1e-9);
  EXPECT_NEAR(x.error_deg.max, y.error_deg.max, 1e-9);
  EXPECT_EQ(x.statistics_samples, y.statistics_samples);
  EXPECT_EQ(x.updates, y.updates);
  EXPECT_NEAR(x.nullspace_active_fraction, y.nullspace_active_fraction, 1e-12);
  EXPECT_EQ(x.failed_updates, y.failed_updates);
  EXPECT_EQ(x.rank_deficient_updates, y.rank_deficient_updates);
  EXPECT_NEAR(x.sigma_min_min, y.sigma_min_min, 1e-9);
  EXPECT_LT((ra.final_phi - rb.final_phi).cwiseAbs().maxCoeff(), 1e-10);
}

INSTANTIATE_TEST_SUITE_P(
    Configurations, FastPathTest,
    ::testing::Values(
        Case{"131", ControlMethod::kGradientProjection, LoopMode::kModel, 0.0, 1e-6},
        Case{"3131", ControlMethod::kGradientProjection, LoopMode::kModel, 0.0, 1e-6},
        Case{"3131", ControlMethod::kThresholdedGradientProjection, LoopMode::kModel, 0.0, 1e-6},
        Case{"131", ControlMethod::kPseudoInverse, LoopMode::kModel, 0.0, 2e-8},
        Case{"3131", ControlMethod::kGradientProjection, LoopMode::kMeasured, 0.05, 1e-6},
        Case{"121", ControlMethod::kGradientProjection, LoopMode::kModel, 0.1, 2e-7},
        Case{"2323", ControlMethod::kPseudoInverse, LoopMode::kMeasured, 0.0, 1e-7}));

TEST(FastPathSelectionTest, OnlyForThePapersClassOfConfigurations) {
  EXPECT_TRUE(ClosedLoopSimulator(Short("131")).uses_fast_path());
  EXPECT_TRUE(ClosedLoopSimulator(Short("3131")).uses_fast_path());

  ScenarioConfig five = Short("13131");
  EXPECT_FALSE(ClosedLoopSimulator(five).uses_fast_path());

  ScenarioConfig rls = Short("131");
  rls.controller.method = ControlMethod::kRegularizedLeastSquares;
  EXPECT_FALSE(ClosedLoopSimulator(rls).uses_fast_path());

  ScenarioConfig ranged = Short("131");
  ranged.stages[1].range = ControlRange{-1.0, 1.0};
  EXPECT_FALSE(ClosedLoopSimulator(ranged).uses_fast_path());

  ScenarioConfig tilted = Short("131");
  tilted.stages[0].axis = Vector3(1, 1, 0);
  EXPECT_FALSE(ClosedLoopSimulator(tilted).uses_fast_path());

  ScenarioConfig polynomial = Short("131");
  polynomial.stages[2].map.kind = ControlMapConfig::Kind::kPolynomial;
  polynomial.stages[2].map.coefficients_rad = {0.0, 3.0, 0.1};
  EXPECT_FALSE(ClosedLoopSimulator(polynomial).uses_fast_path());

  ScenarioConfig set = Short("131");
  set.target.kind = TargetConfig::Kind::kSet;
  EXPECT_FALSE(ClosedLoopSimulator(set).uses_fast_path());

  EXPECT_FALSE(General(Short("131")).uses_fast_path());
}

TEST(FastPathSelectionTest, NearASingularityTheFallbackKeepsBothLoopsTogether) {
  // The 3-stage chain starting at S_in = S1 with stage 1 on S1: σ_min = 0 at first, the
  // closed form is skipped for the Jacobi fallback on those samples.
  ScenarioConfig s = Short("131");
  s.input.disturbances.clear();
  s.input.initial_sop = StokesVector(1, 0, 0);
  s.controller.activation_s = 0.0;
  Recorder a, b;
  const SimulationResult ra = ClosedLoopSimulator(s).Run(&a, 1);
  const SimulationResult rb = General(s).Run(&b, 1);
  EXPECT_EQ(ra.summary.rank_deficient_updates, rb.summary.rank_deficient_updates);
  for (size_t k = 0; k < a.s_out.size(); ++k) {
    ASSERT_LT((a.s_out[k] - b.s_out[k]).norm(), 1e-10) << k;
  }
}

}  // namespace
}  // namespace dpc
