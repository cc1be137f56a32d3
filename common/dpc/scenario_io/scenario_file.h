#pragma once
// Scenario files: read (bounded, regular files only), parsed and converted (scenario_reader.h),
// and validated (LoadScenarioFile).

#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"

namespace dpc {

/// The text of a scenario file. Throws ScenarioError located at `path` if it is not a regular
/// file (a directory, a FIFO, a device: refused without opening, which could block), cannot be
/// read, or exceeds kMaxScenarioTextBytes.
std::string ReadScenarioText(const std::string& path);

/// Reads, parses and converts a scenario file without validating it (for callers that apply
/// overrides first). Throws ScenarioError like LoadScenarioFile, except for field values.
ScenarioConfig ReadScenarioFile(const std::string& path);

/// Reads, parses, converts and validates a scenario file. Throws ScenarioError located at
/// `path` if the file cannot be read, at "path:line:column" for a parse error, and at the field
/// path (see ValidateScenario) for a bad value.
ScenarioConfig LoadScenarioFile(const std::string& path);

}  // namespace dpc
