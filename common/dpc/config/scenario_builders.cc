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

/// Saturates a sample count to [0, INT_MAX] for the law's int settings.
int ToIntSamples(int64_t samples) {
  return static_cast<int>(std::clamp<int64_t>(samples, 0, INT_MAX));
}

/// round(x) as an int, saturated to [0, INT_MAX]; 0 for NaN.
int RoundToIntSamples(double x) {
  if (!(x > 0.0)) return 0;
  if (x >= static_cast<double>(INT_MAX)) return INT_MAX;
  return static_cast<int>(std::lround(x));
}

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

ControlLawConfig BuildControlLawConfig(const ControllerConfig& controller,
                                       const SimulationConfig& simulation) {
  ControlLawConfig config;
  config.method = controller.method;
  config.step = controller.step;
  config.nullspace_step = controller.nullspace_step;
  config.threshold = controller.threshold;
  config.damping = controller.damping;
  config.singular_value_tolerance = controller.singular_value_tolerance;
  if (controller.singularity_damping) {
    config.singularity_damping = controller.singularity_damping->max_damping;
    config.singularity_threshold = controller.singularity_damping->threshold;
  }
  config.range_aware = controller.nullspace_criterion == NullspaceCriterion::kRange;
  config.curvature_correction = controller.curvature_correction;
  const DitherConfig& dither = controller.dither;
  config.dither.amplitude = dither.amplitude;
  config.dither.settle_samples = ToIntSamples(
      dither.settle_samples != 0 ? dither.settle_samples : DelaySamples(simulation));
  config.dither.reset_threshold = dither.reset_threshold;
  config.dither.reset_samples =
      std::max(1, RoundToIntSamples(dither.reset_duration_s * simulation.sample_rate_hz));
  return config;
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
