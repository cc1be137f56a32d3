#pragma once
// Loading the scenario a program runs: a text-format file or a default (the paper's for `dpc`,
// the embedded bench scenario for the services), then the command-line overrides (the `dpc sim`
// flags). Validation is the caller's (the simulator validates the whole scenario, each service
// the whole scenario too).

#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/cli/scenario_overrides.h"

namespace dpc::cli {

/// The scenario in `path` (unvalidated; ReadScenarioFile), or `when_no_file` when `path` is
/// empty, with the overrides applied. Throws ScenarioError.
ScenarioConfig LoadScenarioWithOverrides(const std::string& path, const ScenarioOverrides& overrides,
                                         const ScenarioConfig& when_no_file);

/// "invalid scenario: controller.step: -1 is not > 0 … (set by --step)".
std::string DescribeScenarioError(const ScenarioError& error, const ScenarioOverrides& overrides);

}  // namespace dpc::cli
