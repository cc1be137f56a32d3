#include "dpc/sim/sweep_runner.h"

#include <gtest/gtest.h>

namespace dpc {
namespace {

ScenarioConfig Short(uint64_t seed, double rate) {
  ScenarioConfig s = PaperScenario("131");
  s.simulation.duration_s = 1e-3;
  s.controller.activation_s = 0.2e-3;
  s.simulation.seed = seed;
  s.input.disturbances[0].rate_rad_per_s = rate;
  return s;
}

TEST(SweepRunnerTest, ParallelResultsEqualSeparateRuns) {
  std::vector<ScenarioConfig> scenarios;
  for (uint64_t seed = 1; seed <= 4; ++seed) scenarios.push_back(Short(seed, 1e4 * seed));
  size_t calls = 0;
  const auto outcomes = RunSweep(scenarios, 2, [&](size_t done, size_t total) {
    ++calls;
    EXPECT_LE(done, total);
  });
  ASSERT_EQ(outcomes.size(), 4u);
  EXPECT_EQ(calls, 4u);
  for (size_t i = 0; i < scenarios.size(); ++i) {
    ASSERT_TRUE(outcomes[i].ok) << outcomes[i].error;
    const SimulationResult alone = ClosedLoopSimulator(scenarios[i]).Run();
    EXPECT_EQ(outcomes[i].result.summary.error_deg.mean, alone.summary.error_deg.mean);
    EXPECT_EQ(outcomes[i].result.final_phi, alone.final_phi);
  }
}

TEST(SweepRunnerTest, BatchedRunsOfSeveralKindsEqualSeparateRuns) {
  // 17 runs: 12 that share batches (two durations), a general-path law, another device, an
  // invalid one; in the processor's widest lanes and with batches off.
  std::vector<ScenarioConfig> scenarios;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    ScenarioConfig s = Short(seed, 5e3 * static_cast<double>(seed));
    if (seed % 3 == 0) s.controller.method = ControlMethod::kPseudoInverse;
    if (seed > 8) s.simulation.duration_s = 0.7e-3;
    scenarios.push_back(s);
  }
  ScenarioConfig rls = Short(13, 1e4);
  rls.controller.method = ControlMethod::kRegularizedLeastSquares;
  scenarios.push_back(rls);
  ScenarioConfig four = Short(14, 1e4);
  four.stages = PaperScenario("3131").stages;
  four.controller.initial_phi.clear();
  scenarios.push_back(four);
  scenarios.push_back(Short(15, -1.0));
  scenarios.push_back(Short(16, 2e4));
  scenarios.push_back(Short(17, 3e4));
  for (const char* isa : {"", "none"}) {
    if (*isa != '\0') setenv("DPC_BATCH_ISA", isa, 1);
    const auto outcomes = RunSweep(scenarios, 2);
    unsetenv("DPC_BATCH_ISA");
    ASSERT_EQ(outcomes.size(), scenarios.size());
    for (size_t i = 0; i < scenarios.size(); ++i) {
      SCOPED_TRACE(std::string("run ") + std::to_string(i) + " batches " + (*isa ? isa : "on"));
      if (i == 14) {
        EXPECT_FALSE(outcomes[i].ok);
        continue;
      }
      ASSERT_TRUE(outcomes[i].ok) << outcomes[i].error;
      const SimulationResult alone = ClosedLoopSimulator(scenarios[i]).Run();
      EXPECT_EQ(outcomes[i].result.summary.error_deg.mean, alone.summary.error_deg.mean);
      EXPECT_EQ(outcomes[i].result.summary.error_deg.p99, alone.summary.error_deg.p99);
      EXPECT_EQ(outcomes[i].result.summary.excursions, alone.summary.excursions);
      EXPECT_EQ(outcomes[i].result.summary.samples, alone.summary.samples);
      EXPECT_EQ(outcomes[i].result.final_phi, alone.final_phi);
    }
  }
}

TEST(SweepRunnerTest, InvalidScenariosFailAloneAndStopSkipsTheRest) {
  std::vector<ScenarioConfig> scenarios{Short(1, 1e4), Short(2, -5.0), Short(3, 1e4)};
  const auto outcomes = RunSweep(scenarios, 1);
  EXPECT_TRUE(outcomes[0].ok);
  EXPECT_FALSE(outcomes[1].ok);
  EXPECT_NE(outcomes[1].error.find("rate_rad_per_s"), std::string::npos) << outcomes[1].error;
  EXPECT_TRUE(outcomes[2].ok);
  std::atomic<bool> stop{true};
  const auto skipped = RunSweep(scenarios, 2, {}, &stop);
  for (const auto& o : skipped) EXPECT_EQ(o.error, "skipped");
}

}  // namespace
}  // namespace dpc
