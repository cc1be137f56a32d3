// Runs the paper's 3-stage scenario for 2 ms with the installed core library and prints its
// mean error: what a control engineer's own program would start from.
#include <cstdio>

#include "dpc/config/scenario_config.h"
#include "dpc/sim/closed_loop_simulator.h"

int main() {
  dpc::ScenarioConfig scenario = dpc::PaperScenario("131");
  scenario.simulation.duration_s = 4e-3;
  dpc::ClosedLoopSimulator simulator(scenario);
  const dpc::SimulationResult result = simulator.Run();
  std::printf("samples %lld, mean error %.4f deg, %d controls\n",
              static_cast<long long>(result.summary.samples), result.summary.error_deg.mean,
              static_cast<int>(result.final_phi.size()));
  return result.summary.samples > 0 && result.final_phi.size() == 3 ? 0 : 1;
}
