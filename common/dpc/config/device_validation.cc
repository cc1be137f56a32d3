// The device part of the scenario validation: the stages, their control maps (linear,
// polynomial, lookup table, tables by temperature or wavelength) and control ranges; ValidateDeviceStages and ScenarioControlCount.

#include "dpc/config/scenario_validation.h"

#include <fmt/format.h>

#include <string>

#include "dpc/config/field_checks.h"
#include "dpc/config/scenario_builders.h"

namespace dpc {
namespace {

using field_checks::Fail;
using field_checks::RequireAxis;
using field_checks::RequireFinite;

void ValidateRange(const ControlRange& range, const std::string& path) {
  RequireFinite(range.min, path + ".min", "a control range limit must be finite");
  RequireFinite(range.max, path + ".max", "a control range limit must be finite");
  if (!(range.min < range.max)) {
    Fail(path, fmt::format("[{}, {}] is empty; a control range needs min < max", range.min,
                           range.max));
  }
}

void ValidateLinearMap(const ControlMapConfig& map, const std::string& path) {
  RequireFinite(map.rad_per_unit, path + ".rad_per_unit",
                "the map slope must be finite and non-zero (the paper: π rad per unit)");
  if (map.rad_per_unit == 0.0) {
    Fail(path + ".rad_per_unit",
         "0 rad per unit: the control would do nothing; the slope must be non-zero (the paper: "
         "π rad per unit)");
  }
  RequireFinite(map.offset_rad, path + ".offset_rad", "the map offset must be finite");
}

void ValidatePolynomialMap(const ControlMapConfig& map, const std::string& path) {
  const std::string coefficients_path = path + ".coefficients_rad";
  const auto& c = map.coefficients_rad;
  if (c.size() < 2 || c.size() > static_cast<size_t>(ControlMap::kMaxPolynomialCoefficients)) {
    Fail(coefficients_path,
         fmt::format("{} coefficient(s); a polynomial map needs 2 to {} (constant term first)",
                     c.size(), ControlMap::kMaxPolynomialCoefficients));
  }
  bool has_slope = false;
  for (size_t j = 0; j < c.size(); ++j) {
    RequireFinite(c[j], fmt::format("{}[{}]", coefficients_path, j),
                  "a polynomial coefficient must be finite");
    if (j > 0 && c[j] != 0.0) has_slope = true;
  }
  if (!has_slope) {
    Fail(coefficients_path,
         "every coefficient of degree >= 1 is 0: the map is constant and the control would do "
         "nothing");
  }
}

void ValidateTable(const std::vector<double>& control, const std::vector<double>& angle, const std::string& path) {
  if (control.size() != angle.size()) {
    Fail(path, fmt::format("{} control values but {} angle_rad values; they must pair up",
                           control.size(), angle.size()));
  }
  if (control.size() < 2 || control.size() > static_cast<size_t>(ControlMap::kMaxTablePoints)) {
    Fail(path + ".control", fmt::format("{} point(s); a lookup table needs 2 to {}",
                                        control.size(), ControlMap::kMaxTablePoints));
  }
  for (size_t j = 0; j < control.size(); ++j) {
    RequireFinite(control[j], fmt::format("{}.control[{}]", path, j),
                  "a lookup table value must be finite");
  }
  for (size_t j = 0; j < angle.size(); ++j) {
    RequireFinite(angle[j], fmt::format("{}.angle_rad[{}]", path, j),
                  "a lookup table value must be finite");
  }
  for (size_t j = 1; j < control.size(); ++j) {
    if (!(control[j] > control[j - 1])) {
      Fail(fmt::format("{}.control[{}]", path, j),
           fmt::format("{} after {}; control must be strictly increasing", control[j],
                       control[j - 1]));
    }
  }
  if (angle[1] == angle[0]) {
    Fail(fmt::format("{}.angle_rad[1]", path),
         fmt::format("{} after {} (equal); a lookup table must be strictly monotonic", angle[1],
                     angle[0]));
  }
  const bool increasing = angle[1] > angle[0];
  for (size_t j = 2; j < angle.size(); ++j) {
    const bool ok = increasing ? angle[j] > angle[j - 1] : angle[j] < angle[j - 1];
    if (!ok) {
      Fail(fmt::format("{}.angle_rad[{}]", path, j),
           fmt::format("{} after {} (the table {} before); a lookup table must be strictly "
                       "monotonic",
                       angle[j], angle[j - 1], increasing ? "increases" : "decreases"));
    }
  }
}

void ValidateTableMap(const ControlMapConfig& map, const std::string& path) {
  ValidateTable(map.table_control, map.table_angle_rad, path);
}

void ValidateConditionTables(const ControlMapConfig& map, const std::string& path) {
  const std::string key = ConditionKeyName(map.condition);
  const char* unit = ConditionUnit(map.condition);
  const bool wavelength = map.condition == ControlMapConfig::Condition::kWavelengthNm;
  const auto& tables = map.condition_tables;
  if (tables.size() < 2 || tables.size() > static_cast<size_t>(ControlMapConfig::kMaxConditionTables)) {
    Fail(path + ".tables", fmt::format("{} table(s); a map by condition needs 2 to {} (else use a table)",
                                       tables.size(), ControlMapConfig::kMaxConditionTables));
  }
  bool increasing = true;
  for (size_t i = 0; i < tables.size(); ++i) {
    const std::string table_path = fmt::format("{}.tables[{}]", path, i);
    const double condition = tables[i].condition;
    RequireFinite(condition, table_path + "." + key, "a table's condition must be finite");
    if (wavelength && !(condition > 0.0)) {
      Fail(table_path + "." + key, fmt::format("{} nm; a wavelength must be positive", condition));
    }
    if (i > 0 && !(condition > tables[i - 1].condition)) {
      Fail(table_path + "." + key, fmt::format("{} {} after {} {}; the tables' conditions must be strictly increasing",
                                               condition, unit, tables[i - 1].condition, unit));
    }
    ValidateTable(tables[i].control, tables[i].angle_rad, table_path + ".table");
    const bool this_increasing = tables[i].angle_rad[1] > tables[i].angle_rad[0];
    if (i == 0) increasing = this_increasing;
    if (this_increasing != increasing) {
      Fail(table_path + ".table.angle_rad",
           fmt::format("the table {} while tables[0] {}: interpolating between them would not be monotonic",
                       this_increasing ? "increases" : "decreases", increasing ? "increases" : "decreases"));
    }
  }
  const std::string operating_path = path + ".operating_" + key;
  RequireFinite(map.operating_point, operating_path, "the operating point must be finite");
  if (map.operating_point < tables.front().condition || map.operating_point > tables.back().condition) {
    Fail(operating_path, fmt::format("{} {} is outside the calibrated {}–{} {}: a calibration is not extrapolated "
                                     "(calibrate at this {} too)",
                                     map.operating_point, unit, tables.front().condition, tables.back().condition,
                                     unit, ConditionNoun(map.condition)));
  }
  try {
    ResolveConditionTables(map);
  } catch (const std::invalid_argument& e) {
    Fail(path, e.what());
  }
}

void ValidateMap(const ControlMapConfig& map, const std::string& path) {
  switch (map.kind) {
    case ControlMapConfig::Kind::kLinear: ValidateLinearMap(map, path + ".linear"); return;
    case ControlMapConfig::Kind::kPolynomial:
      ValidatePolynomialMap(map, path + ".polynomial");
      return;
    case ControlMapConfig::Kind::kTable: ValidateTableMap(map, path + ".table"); return;
    case ControlMapConfig::Kind::kTablesByCondition:
      ValidateConditionTables(map, path + ".tables_by_condition");
      return;
  }
  Fail(path, "unknown map kind");
}

void ValidateStageAngle(const StageAngleConfig& angle, const std::string& path) {
  if (angle.controlled) {
    ValidateMap(angle.map, path + ".controlled.map");
    if (angle.range) ValidateRange(*angle.range, path + ".controlled.range");
  } else {
    RequireFinite(angle.fixed_rad, path + ".fixed_rad", "a fixed angle must be finite");
  }
}

void ValidateStages(const std::vector<StageConfig>& stages) {
  if (stages.empty() || stages.size() > static_cast<size_t>(kMaxStages)) {
    Fail("stages", fmt::format("{} stages; a chain needs 1 to {}", stages.size(), kMaxStages));
  }
  for (size_t i = 0; i < stages.size(); ++i) {
    const StageConfig& stage = stages[i];
    const std::string path = fmt::format("stages[{}]", i);
    switch (stage.kind) {
      case StageConfig::Kind::kFixedAxis:
        RequireAxis(stage.axis, path + ".axis_vector");
        ValidateMap(stage.map, path + ".map");
        if (stage.range) ValidateRange(*stage.range, path + ".range");
        break;
      case StageConfig::Kind::kAdjustableAxis: {
        const std::string adjustable = path + ".adjustable_axis";
        if (!stage.retardance.controlled && !stage.orientation.controlled) {
          Fail(adjustable,
               "neither the retardance nor the orientation is controlled; an adjustable-axis "
               "stage needs at least one control signal (e.g. orientation { controlled {} })");
        }
        ValidateStageAngle(stage.retardance, adjustable + ".retardance");
        ValidateStageAngle(stage.orientation, adjustable + ".orientation");
        break;
      }
    }
  }
  const int controls = ScenarioControlCount(stages);
  if (controls > kMaxControls) {
    Fail("stages", fmt::format("{} controls in all; a chain may have at most {}", controls,
                               kMaxControls));
  }
}

}  // namespace

int ScenarioControlCount(const std::vector<StageConfig>& stages) {
  int count = 0;
  for (const StageConfig& stage : stages) {
    if (stage.kind == StageConfig::Kind::kFixedAxis) {
      ++count;
    } else {
      count += (stage.retardance.controlled ? 1 : 0) + (stage.orientation.controlled ? 1 : 0);
    }
  }
  return count;
}

void CollectRanges(const std::vector<StageConfig>& stages,
                   std::vector<std::pair<std::string, const std::optional<ControlRange>*>>* out) {
  for (size_t i = 0; i < stages.size(); ++i) {
    const StageConfig& stage = stages[i];
    const std::string p = fmt::format("stages[{}]", i);
    if (stage.kind == StageConfig::Kind::kFixedAxis) {
      out->emplace_back(p + ".range", &stage.range);
    } else {
      if (stage.retardance.controlled) out->emplace_back(p + ".adjustable_axis.retardance.range", &stage.retardance.range);
      if (stage.orientation.controlled) {
        out->emplace_back(p + ".adjustable_axis.orientation.range", &stage.orientation.range);
      }
    }
  }
}

void ValidateDeviceStages(const std::vector<StageConfig>& stages) { ValidateStages(stages); }

}  // namespace dpc
