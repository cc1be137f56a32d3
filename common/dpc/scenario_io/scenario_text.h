#pragma once
// Scenario files: Protobuf text format (common/proto/dpc/scenario.proto) ↔ dpc::ScenarioConfig.
//
//   text ──ParseScenarioText──▶ scenario::Scenario ──ScenarioFromProto──▶ ScenarioConfig
//   ScenarioConfig ──ScenarioToProto──▶ scenario::Scenario ──(TextFormat)──▶ ScenarioToText
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
// callers may apply overrides first. LoadScenarioFile does the whole chain.
//
// ScenarioToProto writes only the fields that apply to each entry's kind (a linear map's table
// is dropped), every optional field explicitly, and elemental axes as S1/S2/S3; so
// ScenarioFromProto(ScenarioToProto(c)) equals c in every field that applies.

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

/// The message for `config` (its inverse up to the fields that do not apply).
scenario::Scenario ScenarioToProto(const ScenarioConfig& config);

/// `config` in text format, parseable by ParseScenarioText.
std::string ScenarioToText(const ScenarioConfig& config);

/// Reads, parses and converts a scenario file without validating it (for callers that apply
/// overrides first). Throws ScenarioError like LoadScenarioFile, except for field values.
ScenarioConfig ReadScenarioFile(const std::string& path);

/// Reads, parses, converts and validates a scenario file. Throws ScenarioError located at
/// `path` if the file cannot be read or exceeds kMaxScenarioTextBytes, at "path:line:column"
/// for a parse error, and at the field path (see ValidateScenario) for a bad value.
ScenarioConfig LoadScenarioFile(const std::string& path);

}  // namespace dpc
