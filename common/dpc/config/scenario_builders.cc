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
  }
  throw std::invalid_argument("unknown control map kind");
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
