#pragma once
// Loading the scenario a `dpc` command runs: a text-format file or the built-in paper scenario,
// then command-line overrides. Validation happens when the simulator is built.

#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "scenario_overrides.h"

namespace dpc::tools {

/// The scenario in `path` (unvalidated), or PaperScenario("131") when `path` is empty, with the
/// overrides applied. Throws ScenarioError.
ScenarioConfig LoadScenarioWithOverrides(const std::string& path,
                                         const ScenarioOverrides& overrides);

/// "invalid scenario: controller.step: -1 is not > 0 … (set by --step)".
std::string DescribeScenarioError(const ScenarioError& error, const ScenarioOverrides& overrides);

}  // namespace dpc::tools
