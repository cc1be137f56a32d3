#include "dpc/sim/sweep_runner.h"

#include <algorithm>
#include <mutex>
#include <thread>

namespace dpc {

std::vector<SweepOutcome> RunSweep(const std::vector<ScenarioConfig>& scenarios, int threads,
                                   const std::function<void(size_t, size_t)>& progress,
                                   const std::atomic<bool>* stop) {
  std::vector<SweepOutcome> outcomes(scenarios.size());
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = static_cast<int>(std::min<size_t>(static_cast<size_t>(threads), scenarios.size()));
  std::atomic<size_t> next{0};
  size_t finished = 0;
  std::mutex mutex;

  const auto worker = [&] {
    for (size_t i = next++; i < scenarios.size(); i = next++) {
      SweepOutcome& outcome = outcomes[i];
      if (stop != nullptr && stop->load()) {
        outcome.error = "skipped";
      } else {
        try {
          ClosedLoopSimulator simulator(scenarios[i]);
          outcome.result = simulator.Run();
          outcome.ok = true;
        } catch (const std::exception& e) {
          outcome.error = e.what();
        }
      }
      std::lock_guard<std::mutex> lock(mutex);
      ++finished;
      if (progress) progress(finished, scenarios.size());
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& thread : pool) thread.join();
  return outcomes;
}

}  // namespace dpc
