#include "dpc/sim/sweep_runner.h"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "dpc/sim/batch_simulator.h"

namespace dpc {
namespace {

// The work: groups of runs, each a batch (or a run alone). Runs of one key are split into as few
// batches as the lanes allow, but into at least as many as there are threads (while there are
// runs), in even groups, so that every core has work.
std::vector<std::vector<size_t>> PlanWork(const std::vector<ScenarioConfig>& scenarios,
                                          size_t width, size_t threads) {
  std::vector<std::vector<size_t>> work;
  std::map<BatchKey, std::vector<size_t>> by_key;
  std::vector<BatchKey> key_order;
  for (size_t i = 0; i < scenarios.size(); ++i) {
    if (width > 1) {
      try {
        if (const std::optional<BatchKey> key = BatchKeyOf(ClosedLoopSimulator(scenarios[i]))) {
          auto [it, added] = by_key.try_emplace(*key);
          if (added) key_order.push_back(*key);
          it->second.push_back(i);
          continue;
        }
      } catch (const std::exception&) {
        // Runs alone: its worker reports the error.
      }
    }
    work.push_back({i});
  }
  for (const BatchKey& key : key_order) {
    const std::vector<size_t>& runs = by_key[key];
    const size_t groups = std::max((runs.size() + width - 1) / width, std::min(threads, runs.size()));
    for (size_t g = 0, next = 0; g < groups; ++g) {
      const size_t size = runs.size() / groups + (g < runs.size() % groups ? 1 : 0);
      work.emplace_back(runs.begin() + static_cast<ptrdiff_t>(next),
                        runs.begin() + static_cast<ptrdiff_t>(next + size));
      next += size;
    }
  }
  // The largest groups first, so that the last to finish are short.
  std::stable_sort(work.begin(), work.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return work;
}

}  // namespace

int SweepThreads(int threads, size_t runs) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return static_cast<int>(std::min<size_t>(static_cast<size_t>(threads), runs));
}

std::vector<SweepOutcome> RunSweep(const std::vector<ScenarioConfig>& scenarios, int threads,
                                   const std::function<void(size_t, size_t)>& progress,
                                   const std::atomic<bool>* stop) {
  std::vector<SweepOutcome> outcomes(scenarios.size());
  threads = SweepThreads(threads, scenarios.size());
  const BatchIsa isa = ChosenBatchIsa();
  const std::vector<std::vector<size_t>> work =
      PlanWork(scenarios, static_cast<size_t>(BatchLanesOf(isa)), static_cast<size_t>(threads));
  std::atomic<size_t> next{0};
  size_t finished = 0;
  std::mutex mutex;

  const auto run_alone = [&](size_t i) {
    SweepOutcome& outcome = outcomes[i];
    try {
      ClosedLoopSimulator simulator(scenarios[i]);
      outcome.result = simulator.Run();
      outcome.ok = true;
    } catch (const std::exception& e) {
      outcome.error = e.what();
    }
  };
  const auto run_batch = [&](const std::vector<size_t>& runs) {
    try {
      std::vector<std::unique_ptr<ClosedLoopSimulator>> simulators;
      std::vector<const ClosedLoopSimulator*> lanes;
      for (size_t i : runs) {
        simulators.push_back(std::make_unique<ClosedLoopSimulator>(scenarios[i]));
        lanes.push_back(simulators.back().get());
      }
      std::vector<SimulationResult> results = RunBatch(lanes, isa);
      for (size_t l = 0; l < runs.size(); ++l) {
        outcomes[runs[l]].result = std::move(results[l]);
        outcomes[runs[l]].ok = true;
      }
    } catch (const std::exception& e) {
      for (size_t i : runs) outcomes[i].error = e.what();
    }
  };
  const auto worker = [&] {
    for (size_t w = next++; w < work.size(); w = next++) {
      const std::vector<size_t>& runs = work[w];
      if (stop != nullptr && stop->load()) {
        for (size_t i : runs) outcomes[i].error = "skipped";
      } else if (runs.size() == 1) {
        run_alone(runs[0]);
      } else {
        run_batch(runs);
      }
      std::lock_guard<std::mutex> lock(mutex);
      for (size_t r = 0; r < runs.size(); ++r) {
        ++finished;
        if (progress) progress(finished, scenarios.size());
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& thread : pool) thread.join();
  return outcomes;
}

}  // namespace dpc
