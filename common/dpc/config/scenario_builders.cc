#include "dpc/config/scenario_builders.h"

#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

StageAngle BuildStageAngle(const StageAngleConfig& config) {
  if (!config.controlled) return StageAngle::Fixed(config.fixed_rad);
  return StageAngle::Controlled(BuildControlMap(config.map), config.range);
}

WaveplateStage BuildStage(const StageConfig& config) {
  switch (config.kind) {
    case StageConfig::Kind::kFixedAxis:
      return WaveplateStage::FixedAxis(config.axis, BuildControlMap(config.map), config.range,
                                       config.name);
    case StageConfig::Kind::kAdjustableAxis:
      return WaveplateStage::AdjustableAxis(BuildStageAngle(config.retardance),
                                            BuildStageAngle(config.orientation), config.name);
  }
  throw std::invalid_argument("unknown stage kind");
}

}  // namespace

ControlMap BuildControlMap(const ControlMapConfig& config) {
  switch (config.kind) {
    case ControlMapConfig::Kind::kLinear:
      return ControlMap::Linear(config.rad_per_unit, config.offset_rad);
    case ControlMapConfig::Kind::kPolynomial:
      return ControlMap::Polynomial(config.coefficients_rad);
    case ControlMapConfig::Kind::kTable:
      return ControlMap::Table(config.table_control, config.table_angle_rad);
    case ControlMapConfig::Kind::kTablesByCondition: {
      const ControlMapConfig table = ResolveConditionTables(config);
      return ControlMap::Table(table.table_control, table.table_angle_rad);
    }
  }
  throw std::invalid_argument("unknown control map kind");
}

const char* ConditionKeyName(ControlMapConfig::Condition condition) {
  return condition == ControlMapConfig::Condition::kWavelengthNm ? "wavelength_nm" : "temperature_c";
}

const char* ConditionUnit(ControlMapConfig::Condition condition) {
  return condition == ControlMapConfig::Condition::kWavelengthNm ? "nm" : "°C";
}

const char* ConditionNoun(ControlMapConfig::Condition condition) {
  return condition == ControlMapConfig::Condition::kWavelengthNm ? "wavelength" : "temperature";
}

ControlMapConfig ResolveConditionTables(const ControlMapConfig& config) {
  if (config.kind != ControlMapConfig::Kind::kTablesByCondition) return config;
  const std::vector<ConditionTableConfig>& tables = config.condition_tables;
  const char* unit = ConditionUnit(config.condition);
  if (tables.size() < 2) {
    throw std::invalid_argument(fmt::format("{} table(s); a map by condition needs at least 2", tables.size()));
  }
  const double at = config.operating_point;
  if (!(std::isfinite(at) && at >= tables.front().condition && at <= tables.back().condition)) {
    throw std::invalid_argument(fmt::format("the operating point {:g} {} is outside the calibrated {:g}–{:g} {} (a "
                                            "calibration is not extrapolated: calibrate there too)",
                                            at, unit, tables.front().condition, tables.back().condition, unit));
  }
  size_t upper = 1;
  while (upper + 1 < tables.size() && at > tables[upper].condition) ++upper;
  const ConditionTableConfig& a = tables[upper - 1];
  const ConditionTableConfig& b = tables[upper];
  ControlMapConfig resolved;
  resolved.kind = ControlMapConfig::Kind::kTable;
  if (at == a.condition || at == b.condition) {
    const ConditionTableConfig& exact = at == a.condition ? a : b;
    resolved.table_control = exact.control;
    resolved.table_angle_rad = exact.angle_rad;
    ControlMap::Table(resolved.table_control, resolved.table_angle_rad);  // throws if invalid
    return resolved;
  }
  // A retardance goes as 1/λ: wavelengths are interpolated in 1/λ.
  const auto key = [&](double condition) {
    return config.condition == ControlMapConfig::Condition::kWavelengthNm ? 1.0 / condition : condition;
  };
  const double weight = (key(at) - key(a.condition)) / (key(b.condition) - key(a.condition));
  const ControlMap map_a = ControlMap::Table(a.control, a.angle_rad);
  const ControlMap map_b = ControlMap::Table(b.control, b.angle_rad);
  std::vector<double> control = a.control;
  control.insert(control.end(), b.control.begin(), b.control.end());
  std::sort(control.begin(), control.end());
  control.erase(std::unique(control.begin(), control.end()), control.end());
  if (control.size() > static_cast<size_t>(ControlMap::kMaxTablePoints)) {
    throw std::invalid_argument(fmt::format("the tables at {:g} and {:g} {} have {} distinct control points together, "
                                            "more than the {} of a table",
                                            a.condition, b.condition, unit, control.size(),
                                            ControlMap::kMaxTablePoints));
  }
  resolved.table_control = control;
  resolved.table_angle_rad.reserve(control.size());
  for (const double phi : control) {
    resolved.table_angle_rad.push_back((1.0 - weight) * map_a.AngleRad(phi) + weight * map_b.AngleRad(phi));
  }
  ControlMap::Table(resolved.table_control, resolved.table_angle_rad);  // throws if not monotonic
  return resolved;
}

WaveplateChain BuildChain(const std::vector<StageConfig>& stages) {
  std::vector<WaveplateStage> built;
  built.reserve(stages.size());
  for (size_t i = 0; i < stages.size(); ++i) {
    try {
      built.push_back(BuildStage(stages[i]));
    } catch (const std::invalid_argument& e) {
      throw ScenarioError(fmt::format("stages[{}]", i), e.what());
    }
  }
  try {
    return WaveplateChain(std::move(built));
  } catch (const std::invalid_argument& e) {
    throw ScenarioError("stages", e.what());
  }
}

Target BuildTarget(const TargetConfig& config) {
  try {
    switch (config.kind) {
      case TargetConfig::Kind::kPoint: return Target::Point(config.point);
      case TargetConfig::Kind::kSet: return Target::Set(config.normal, config.offset);
    }
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(config.kind == TargetConfig::Kind::kPoint ? "target.point" : "target.set",
                        e.what());
  }
  throw ScenarioError("target", "unknown target kind");
}

LawTiming BuildLawTiming(const SimulationConfig& simulation) {
  return LawTiming{simulation.sample_rate_hz, DelaySamples(simulation)};
}

ControlVector BuildInitialPhi(const ControllerConfig& controller, int control_count) {
  if (control_count < 0 || control_count > kMaxControls) {
    throw ScenarioError("controller.initial_phi",
                        fmt::format("{} controls; a chain has 0 to {}", control_count,
                                    kMaxControls));
  }
  const auto& phi = controller.initial_phi;
  if (phi.empty()) return ControlVector::Zero(control_count);
  if (phi.size() != static_cast<size_t>(control_count)) {
    throw ScenarioError("controller.initial_phi",
                        fmt::format("{} value(s) for {} control(s); give exactly one per "
                                    "control, or none for all zeros",
                                    phi.size(), control_count));
  }
  ControlVector result(control_count);
  for (int j = 0; j < control_count; ++j) result[j] = phi[static_cast<size_t>(j)];
  return result;
}

}  // namespace dpc
