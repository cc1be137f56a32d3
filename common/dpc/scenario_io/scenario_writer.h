#pragma once
// Writing scenarios: ScenarioConfig → Protobuf text format (common/proto/dpc/scenario.proto),
// as `dpc sim --print-scenario` shows the effective scenario.
//
//   ScenarioConfig ──ScenarioToProto──▶ scenario::Scenario ──(TextFormat)──▶ ScenarioToText
//
// ScenarioToProto writes only the fields that apply to each entry's kind (a linear map's table
// is dropped), every optional field explicitly, and elemental axes as S1/S2/S3; so
// ScenarioFromProto(ScenarioToProto(c)) (scenario_reader.h) equals c in every field that
// applies.

#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "scenario.pb.h"

namespace dpc {

/// The message for `config` (the reader's inverse up to the fields that do not apply).
scenario::Scenario ScenarioToProto(const ScenarioConfig& config);

/// `config` in text format, parseable by ParseScenarioText. Throws ScenarioError if protobuf
/// cannot print it.
std::string ScenarioToText(const ScenarioConfig& config);

}  // namespace dpc
