#include "dpc/sim/batch_simulator.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "support/run_summary_expect.h"

namespace dpc {
namespace {

void ExpectSameFinalPhi(const SimulationResult& batch, const SimulationResult& scalar) {
  ASSERT_EQ(batch.final_phi.size(), scalar.final_phi.size());
  for (Eigen::Index e = 0; e < batch.final_phi.size(); ++e) {
    EXPECT_SAME_BITS(batch.final_phi[e], scalar.final_phi[e]);
  }
}

void ExpectSameSummary(const SimulationResult& batch, const SimulationResult& scalar,
                       const std::string& what) {
  SCOPED_TRACE(what);
  ExpectSameRunSummary(batch.summary, scalar.summary);
  ExpectSameFinalPhi(batch, scalar);
}

ScenarioConfig Short(const char* axes, uint64_t seed) {
  ScenarioConfig s = PaperScenario(axes);
  s.simulation.duration_s = 1.3e-3;  // 65000 samples: the last block is partial
  s.controller.activation_s = 0.1e-3;
  s.simulation.settle_samples = 100;
  s.simulation.seed = seed;
  s.input.disturbances[0].rate_rad_per_s = 3e4;
  return s;
}

std::vector<BatchIsa> AvailableIsas() {
  std::vector<BatchIsa> isas;
  if (DetectBatchIsa() >= BatchIsa::kAvx2) isas.push_back(BatchIsa::kAvx2);
  if (DetectBatchIsa() >= BatchIsa::kAvx512) isas.push_back(BatchIsa::kAvx512);
  return isas;
}

// Each lane of a batch of different runs (seeds, rates, laws, loops, noise, steps, targets)
// equals that run alone, for every instruction set the processor has.
void ExpectLanesEqualScalarRuns(const std::vector<ScenarioConfig>& scenarios) {
  const std::vector<BatchIsa> isas = AvailableIsas();
  if (isas.empty()) GTEST_SKIP() << "this processor has neither AVX2 nor AVX-512";
  std::vector<std::unique_ptr<ClosedLoopSimulator>> simulators;
  std::vector<SimulationResult> scalar;
  for (const ScenarioConfig& s : scenarios) {
    simulators.push_back(std::make_unique<ClosedLoopSimulator>(s));
    ASSERT_TRUE(simulators.back()->uses_fast_path());
    scalar.push_back(simulators.back()->Run());
  }
  for (BatchIsa isa : isas) {
    const size_t width = static_cast<size_t>(BatchLanesOf(isa));
    for (size_t first = 0; first < simulators.size(); first += width) {
      std::vector<const ClosedLoopSimulator*> lanes;
      for (size_t i = first; i < std::min(simulators.size(), first + width); ++i) {
        lanes.push_back(simulators[i].get());
      }
      const std::vector<SimulationResult> batch = RunBatch(lanes, isa);
      ASSERT_EQ(batch.size(), lanes.size());
      for (size_t l = 0; l < lanes.size(); ++l) {
        ExpectSameSummary(batch[l], scalar[first + l],
                          std::string(BatchIsaName(isa)) + " run " + std::to_string(first + l));
      }
    }
  }
}

std::vector<ScenarioConfig> Mixed(const char* axes) {
  std::vector<ScenarioConfig> scenarios;
  const ControlMethod methods[] = {ControlMethod::kGradientProjection,
                                   ControlMethod::kThresholdedGradientProjection,
                                   ControlMethod::kPseudoInverse};
  for (int i = 0; i < 11; ++i) {  // 11 lanes: a full batch and a padded one
    ScenarioConfig s = Short(axes, 1 + static_cast<uint64_t>(i));
    s.controller.method = methods[i % 3];
    s.controller.threshold = 0.3;  // gpt switches its null-space term on and off
    s.input.disturbances[0].rate_rad_per_s = 1e4 * (1 + i);
    if (i % 4 == 1) {
      s.controller.loop = LoopMode::kMeasured;
      s.controller.step = 0.02;
      s.simulation.polarimeter_noise_deg = 0.05;
    }
    if (i % 5 == 2) s.controller.nullspace_step = 0.05;
    if (i == 7) s.target.point = StokesVector(0.0, 0.0, 1.0);
    scenarios.push_back(s);
  }
  return scenarios;
}

TEST(BatchSimulatorTest, EveryLaneEqualsItsRunAloneOnThePapersFourStages) {
  ExpectLanesEqualScalarRuns(Mixed("3131"));
}

TEST(BatchSimulatorTest, EveryLaneEqualsItsRunAloneOnThePapersThreeStages) {
  ExpectLanesEqualScalarRuns(Mixed("131"));
}

TEST(BatchSimulatorTest, EveryLaneEqualsItsRunAloneOnOtherAxesAndDelays) {
  for (const char* axes : {"121", "2323"}) {
    for (double delay_s : {2e-8 /* one sample */, 2e-7}) {
      std::vector<ScenarioConfig> scenarios = Mixed(axes);
      for (ScenarioConfig& s : scenarios) s.simulation.delay_s = delay_s;
      SCOPED_TRACE(std::string(axes) + " delay " + std::to_string(delay_s));
      ExpectLanesEqualScalarRuns(scenarios);
    }
  }
}

TEST(BatchSimulatorTest, ALaneNearASingularityTakesTheScalarFallback) {
  // S_in = S1 at a stage on S1: σ_min = 0 at first, the closed form gives way to the Jacobi
  // fallback in that lane only.
  std::vector<ScenarioConfig> scenarios = Mixed("131");
  scenarios.resize(4);
  scenarios[2].input.disturbances.clear();
  scenarios[2].input.initial_sop = StokesVector(1, 0, 0);
  for (ScenarioConfig& s : scenarios) s.controller.activation_s = 0.0;
  const SimulationResult alone = ClosedLoopSimulator(scenarios[2]).Run();
  ASSERT_GT(alone.summary.rank_deficient_updates + alone.summary.failed_updates, 0);
  ExpectLanesEqualScalarRuns(scenarios);
}

// The kernel alone (what dpc_benchmark's BatchKernel measures) does a run's control work: without
// the scrambler's kicks (no normal draws to reuse) its lanes end at the run's φ, bit for bit, and
// it keeps no statistics.
TEST(BatchSimulatorTest, TheKernelAloneTakesTheRunsTrajectoryAndKeepsNoStatistics) {
  const std::vector<BatchIsa> isas = AvailableIsas();
  if (isas.empty()) GTEST_SKIP() << "this processor has neither AVX2 nor AVX-512";
  std::vector<ScenarioConfig> scenarios = Mixed("3131");
  scenarios.resize(4);
  for (ScenarioConfig& s : scenarios) s.input.disturbances[0].kick_rms_ratio = 0.0;
  std::vector<std::unique_ptr<ClosedLoopSimulator>> simulators;
  std::vector<const ClosedLoopSimulator*> lanes;
  for (const ScenarioConfig& s : scenarios) {
    simulators.push_back(std::make_unique<ClosedLoopSimulator>(s));
    lanes.push_back(simulators.back().get());
  }
  for (BatchIsa isa : isas) {
    SCOPED_TRACE(BatchIsaName(isa));
    const std::vector<SimulationResult> run = RunBatch(lanes, isa);
    const std::vector<SimulationResult> kernel = RunBatch(lanes, isa, BatchParts::kKernelOnly);
    ASSERT_EQ(kernel.size(), run.size());
    for (size_t l = 0; l < run.size(); ++l) {
      ASSERT_GT(run[l].summary.statistics_samples, 0);
      EXPECT_EQ(kernel[l].summary.statistics_samples, 0);
      EXPECT_EQ(kernel[l].summary.updates, 0);
      ExpectSameFinalPhi(kernel[l], run[l]);
    }
  }
}

TEST(BatchSimulatorTest, RunsThatCannotShareABatchAreRefused) {
  const std::vector<BatchIsa> isas = AvailableIsas();
  if (isas.empty()) GTEST_SKIP() << "this processor has neither AVX2 nor AVX-512";
  const ClosedLoopSimulator four(Short("3131", 1)), three(Short("131", 1));
  ScenarioConfig longer_config = Short("3131", 2);
  longer_config.simulation.duration_s = 2e-3;
  const ClosedLoopSimulator longer(longer_config);
  ScenarioConfig general_config = Short("3131", 3);
  general_config.controller.method = ControlMethod::kRegularizedLeastSquares;
  const ClosedLoopSimulator general(general_config);
  EXPECT_FALSE(CanShareBatch(four, three));
  EXPECT_FALSE(CanShareBatch(four, longer));
  EXPECT_FALSE(CanShareBatch(four, general));
  EXPECT_TRUE(CanShareBatch(four, four));
  const std::vector<const ClosedLoopSimulator*> mixed = {&four, &three};
  EXPECT_THROW(RunBatch(mixed, isas[0]), std::invalid_argument);
  const std::vector<const ClosedLoopSimulator*> too_many(9, &four);
  EXPECT_THROW(RunBatch(too_many, isas.back()), std::invalid_argument);
  EXPECT_THROW(RunBatch(mixed, BatchIsa::kNone), std::invalid_argument);
}

TEST(BatchSimulatorTest, TheEnvironmentNarrowsTheInstructionSet) {
  const BatchIsa detected = DetectBatchIsa();
  setenv("DPC_BATCH_ISA", "none", 1);
  EXPECT_EQ(ChosenBatchIsa(), BatchIsa::kNone);
  setenv("DPC_BATCH_ISA", "avx2", 1);
  EXPECT_EQ(ChosenBatchIsa(), std::min(detected, BatchIsa::kAvx2));
  setenv("DPC_BATCH_ISA", "avx512", 1);
  EXPECT_EQ(ChosenBatchIsa(), detected);
  unsetenv("DPC_BATCH_ISA");
  EXPECT_EQ(ChosenBatchIsa(), detected);
  EXPECT_EQ(BatchLanesOf(BatchIsa::kAvx512), 8);
  EXPECT_EQ(BatchLanesOf(BatchIsa::kAvx2), 4);
  EXPECT_EQ(BatchLanesOf(BatchIsa::kNone), 1);
}

}  // namespace
}  // namespace dpc
