#include "dpc/config/scenario_config.h"

#include <fmt/format.h>

#include <stdexcept>

namespace dpc {

std::vector<StageConfig> StagesFromAxes(const std::string& axes) {
  std::vector<StageConfig> stages;
  for (char ch : axes) {
    StageConfig stage;
    switch (ch) {
      case '1': stage.axis = Vector3::UnitX(); break;
      case '2': stage.axis = Vector3::UnitY(); break;
      case '3': stage.axis = Vector3::UnitZ(); break;
      default:
        throw std::invalid_argument(fmt::format(
            "stage axes \"{}\": '{}' is not an axis; use 1, 2 or 3 for S1, S2, S3", axes, ch));
    }
    stages.push_back(stage);
  }
  return stages;
}

ScenarioConfig PaperScenario(const std::string& axes) {
  ScenarioConfig scenario;
  scenario.name = "paper-" + axes;
  scenario.description =
      "Wang et al., Jacobian methods for DPC, section IV: input rotating about S3 at 100 krad/s "
      "with random kicks about S2, 50 MHz sampling, 1 us loop delay, gradient projection from "
      "2 ms, target [0, 0.6, 0.8].";
  scenario.stages = StagesFromAxes(axes);
  scenario.input.disturbances.push_back(DisturbanceConfig{});  // paper scrambler, 100 krad/s
  return scenario;
}

}  // namespace dpc
