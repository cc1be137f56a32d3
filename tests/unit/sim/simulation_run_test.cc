#include "dpc/sim/simulation_run.h"

#include <gtest/gtest.h>

namespace dpc {
namespace {

class Counting : public SimulationObserver {
 public:
  bool OnProgress(int64_t done, int64_t total) override {
    calls.emplace_back(done, total);
    return done < stop_at;
  }
  bool wants_samples() const override { return samples; }
  std::vector<std::pair<int64_t, int64_t>> calls;
  int64_t stop_at = INT64_MAX;
  bool samples = true;
};

const Target kTarget = Target::Point(StokesVector(0, 0.6, 0.8));

TEST(SimulationRunTest, DecimatesSamplesForTheObserver) {
  Counting observer;
  SimulationRun run(PaperScenario("131"), kTarget, 3, 1000, &observer, 4);
  std::vector<int> taken;
  for (int k = 0; k < 10; ++k) {
    if (run.TakesSample()) taken.push_back(k);
  }
  EXPECT_EQ(taken, (std::vector<int>{0, 4, 8}));
  observer.samples = false;
  SimulationRun quiet(PaperScenario("131"), kTarget, 3, 1000, &observer, 1);
  EXPECT_FALSE(quiet.TakesSample());
  SimulationRun none(PaperScenario("131"), kTarget, 3, 1000, nullptr, 1);
  EXPECT_FALSE(none.TakesSample());
}

TEST(SimulationRunTest, ReportsProgressAndStops) {
  Counting observer;
  const int64_t interval = ClosedLoopSimulator::kProgressInterval;
  observer.stop_at = 2 * interval;
  SimulationRun run(PaperScenario("131"), kTarget, 3, 10 * interval, &observer, 1);
  EXPECT_TRUE(run.EndBlock(interval - 1));
  EXPECT_TRUE(observer.calls.empty());
  EXPECT_TRUE(run.EndBlock(interval + 5));
  EXPECT_FALSE(run.EndBlock(2 * interval + 7));
  ASSERT_EQ(observer.calls.size(), 2u);
  EXPECT_EQ(observer.calls[1].first, 2 * interval + 7);
  const SimulationResult result = run.Finish(2 * interval + 7, 3, ControlVector::Zero(3));
  EXPECT_TRUE(result.stopped_early);
  EXPECT_EQ(result.summary.samples, 2 * interval + 7);
  EXPECT_EQ(result.summary.resets, 3);
  EXPECT_EQ(observer.calls.size(), 2u);  // no final call after a stop
}

TEST(SimulationRunTest, FinishReportsTheLastProgressAndTheSpeed) {
  Counting observer;
  SimulationRun run(PaperScenario("131"), kTarget, 3, 500, &observer, 1);
  const SimulationResult result = run.Finish(500, 0, ControlVector::Ones(3));
  ASSERT_EQ(observer.calls.size(), 1u);
  EXPECT_EQ(observer.calls[0], std::make_pair(int64_t{500}, int64_t{500}));
  EXPECT_FALSE(result.stopped_early);
  EXPECT_GT(result.samples_per_s, 0.0);
  EXPECT_EQ(result.final_phi, ControlVector::Ones(3));
}

}  // namespace
}  // namespace dpc
