#pragma once
// Reading scenario files: Protobuf text format (common/proto/dpc/scenario.proto) → ScenarioConfig.
//
//   text ──ParseScenarioText──▶ scenario::Scenario ──ScenarioFromProto──▶ ScenarioConfig
//
// ParseScenarioText reports syntax errors, unknown fields, unknown enum names and singular
// fields given twice as ScenarioError located at "source:line:column" (1-based) with
// protobuf's message, which names the field.
//
// ScenarioFromProto applies the defaults documented in scenario.proto for unset optional
// fields, unset oneofs and *_UNSPECIFIED enums (an unset axis → that message's default axis,
// an unset map → linear π rad per unit, an unset StageAngle → fixed at 0 rad, an unset target
// → the point [0, 0.6, 0.8], an unset set normal → S3), and throws ScenarioError at the field
// for structural conflicts (a stage with both a fixed axis and adjustable_axis; a disturbance
// with no kind; an enum number the schema does not define). It does not call ValidateScenario:
// callers may apply overrides first. Files: scenario_file.h (LoadScenarioFile does the whole
// chain); the other direction: scenario_writer.h.

#include <cstddef>
#include <string>
#include <string_view>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "scenario.pb.h"

namespace dpc {

/// The largest scenario text accepted, bytes.
inline constexpr std::size_t kMaxScenarioTextBytes = 16u << 20;  // 16 MiB

/// Parses text format. `source_name` (a file name, or e.g. "<override>") prefixes error
/// locations: "source_name:line:column". Throws ScenarioError on any parse error, or (at
/// `source_name`) if the text is larger than kMaxScenarioTextBytes.
scenario::Scenario ParseScenarioText(std::string_view text, const std::string& source_name);

/// The plain struct with the schema's defaults applied. Throws ScenarioError for structural
/// conflicts (see above). Does not validate values.
ScenarioConfig ScenarioFromProto(const scenario::Scenario& proto);

}  // namespace dpc
