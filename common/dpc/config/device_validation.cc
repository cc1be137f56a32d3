// The device part of the scenario validation: the stages, their control maps (linear,
// polynomial, lookup table) and control ranges; ValidateDeviceStages and ScenarioControlCount.

#include "dpc/config/scenario_validation.h"

#include <fmt/format.h>

#include <string>

#include "dpc/config/field_checks.h"

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

void ValidateTableMap(const ControlMapConfig& map, const std::string& path) {
  const auto& control = map.table_control;
  const auto& angle = map.table_angle_rad;
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

void ValidateMap(const ControlMapConfig& map, const std::string& path) {
  switch (map.kind) {
    case ControlMapConfig::Kind::kLinear: ValidateLinearMap(map, path + ".linear"); return;
    case ControlMapConfig::Kind::kPolynomial:
      ValidatePolynomialMap(map, path + ".polynomial");
      return;
    case ControlMapConfig::Kind::kTable: ValidateTableMap(map, path + ".table"); return;
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

void ValidateDeviceStages(const std::vector<StageConfig>& stages) { ValidateStages(stages); }

}  // namespace dpc
