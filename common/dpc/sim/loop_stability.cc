#include "dpc/sim/loop_stability.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "dpc/config/scenario_validation.h"

namespace dpc {

double MeasuredLoopStepLimit(int64_t delay_samples) {
  if (delay_samples < 1) {
    throw std::invalid_argument(
        fmt::format("loop delay must be at least one sample (got {})", delay_samples));
  }
  return 2.0 * std::sin(M_PI / (2.0 * (2.0 * static_cast<double>(delay_samples) - 1.0)));
}

std::vector<std::string> ScenarioWarnings(const ScenarioConfig& scenario) {
  std::vector<std::string> warnings;
  const ControllerConfig& c = scenario.controller;
  const int64_t delay = DelaySamples(scenario.simulation);
  const bool gain_is_step = c.method != ControlMethod::kTranspose &&
                            c.method != ControlMethod::kDither &&
                            c.method != ControlMethod::kInverse;
  if (c.loop == LoopMode::kMeasured && gain_is_step) {
    const double limit = MeasuredLoopStepLimit(delay);
    if (c.step >= limit) {
      warnings.push_back(fmt::format(
          "controller.step {:g} is at or above the stability limit {:.4g} of the measured loop "
          "with a {}-sample delay (2·sin(π/(2(2D−1)))): the loop will oscillate; use a step "
          "below it or loop: MODEL",
          c.step, limit, delay));
    }
  }
  if (c.loop == LoopMode::kModel && gain_is_step && c.step >= 2.0) {
    warnings.push_back(fmt::format(
        "controller.step {:g} >= 2: the model loop is unstable for steps outside (0, 2)", c.step));
  }
  if (c.method == ControlMethod::kInverse) {
    warnings.push_back(
        "method inverse: every 3-stage Jacobian is singular (its columns are all ⊥ S_out), so "
        "the law reports a singularity and applies nothing on every sample: expect no lock");
  }
  if (c.method == ControlMethod::kDither && c.loop == LoopMode::kModel) {
    warnings.push_back(
        "method dither is model-free: it always uses the measured output; loop mode is ignored");
  }
  return warnings;
}

}  // namespace dpc
