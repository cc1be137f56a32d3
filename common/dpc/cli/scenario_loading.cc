#include "dpc/cli/scenario_loading.h"

#include <fmt/format.h>

#include "dpc/scenario_io/scenario_file.h"

namespace dpc::cli {

ScenarioConfig LoadScenarioWithOverrides(const std::string& path, const ScenarioOverrides& overrides,
                                         const ScenarioConfig& when_no_file) {
  ScenarioConfig scenario = path.empty() ? when_no_file : ReadScenarioFile(path);
  overrides.Apply(&scenario);
  return scenario;
}

std::string DescribeScenarioError(const ScenarioError& error, const ScenarioOverrides& overrides) {
  std::string text = fmt::format("invalid scenario: {}", error.what());
  if (const auto flag = overrides.FlagForField(error.location())) {
    text += fmt::format(" (set by {})", *flag);
  }
  return text;
}

}  // namespace dpc::cli
