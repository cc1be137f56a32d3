#include "dpc/control/control_law_factory.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "dpc/control/extended_jacobian_law.h"
#include "dpc/control/gradient_projection_law.h"
#include "dpc/control/jacobian_laws.h"

namespace dpc {
namespace {

constexpr std::array<std::pair<ControlMethod, std::string_view>, 9> kMethodNames{{
    {ControlMethod::kInverse, "inverse"},
    {ControlMethod::kTranspose, "transpose"},
    {ControlMethod::kDamped, "damped"},
    {ControlMethod::kPseudoInverse, "pinv"},
    {ControlMethod::kRegularizedLeastSquares, "rls"},
    {ControlMethod::kGradientProjection, "gp"},
    {ControlMethod::kThresholdedGradientProjection, "gpt"},
    {ControlMethod::kExtendedJacobian, "extended"},
    {ControlMethod::kDither, "dither"},
}};

}  // namespace

std::string_view MethodName(ControlMethod method) {
  for (const auto& [m, name] : kMethodNames) {
    if (m == method) return name;
  }
  return "unknown";
}

std::optional<ControlMethod> ParseMethod(std::string_view name) {
  for (const auto& [m, method_name] : kMethodNames) {
    if (method_name == name) return m;
  }
  return std::nullopt;
}

std::string_view MethodNameList() { return "inverse|transpose|damped|pinv|rls|gp|gpt|extended|dither"; }

DitherSettings BuildDitherSettings(const DitherConfig& dither, const LawTiming& timing) {
  const auto saturate = [](double samples) {
    if (!(samples > 0.0)) return 0;
    if (samples >= static_cast<double>(INT_MAX)) return INT_MAX;
    return static_cast<int>(std::lround(samples));
  };
  DitherSettings settings;
  settings.amplitude = dither.amplitude;
  settings.settle_samples = static_cast<int>(std::clamp<int64_t>(
      dither.settle_samples != 0 ? dither.settle_samples : timing.delay_samples, 0, INT_MAX));
  settings.reset_threshold = dither.reset_threshold;
  settings.reset_samples = std::max(1, saturate(dither.reset_duration_s * timing.sample_rate_hz));
  return settings;
}

std::unique_ptr<ControlLaw> MakeControlLaw(const ControllerConfig& config, const LawTiming& timing,
                                           int control_count, bool point_target) {
  const auto require_square = [&](std::string_view method) {
    const int task_rows = point_target ? 3 : 1;
    if (control_count != task_rows) {
      throw std::invalid_argument(fmt::format(
          "method {} inverts a square task matrix: it needs {} control(s) for a {} target "
          "(this chain has {}); use pinv, rls or gp",
          method, task_rows, point_target ? "point" : "set", control_count));
    }
  };
  switch (config.method) {
    case ControlMethod::kInverse:
      require_square("inverse");
      return std::make_unique<InverseJacobianLaw>(config.step);
    case ControlMethod::kTranspose:
      return std::make_unique<TransposeJacobianLaw>(config.step);
    case ControlMethod::kDamped:
      require_square("damped");
      return std::make_unique<DampedJacobianLaw>(config.step, config.damping);
    case ControlMethod::kPseudoInverse:
      return std::make_unique<PseudoInverseLaw>(config.step, config.singular_value_tolerance);
    case ControlMethod::kRegularizedLeastSquares:
      return std::make_unique<RegularizedLeastSquaresLaw>(config.step, config.damping);
    case ControlMethod::kGradientProjection:
    case ControlMethod::kThresholdedGradientProjection: {
      GradientProjectionOptions options;
      if (config.method == ControlMethod::kThresholdedGradientProjection) {
        options.threshold = config.threshold;
      }
      options.singular_value_tolerance = config.singular_value_tolerance;
      if (config.singularity_damping) {
        options.max_damping = config.singularity_damping->max_damping;
        options.damping_threshold = config.singularity_damping->threshold;
      }
      options.range_aware = config.nullspace_criterion == NullspaceCriterion::kRange;
      options.curvature_correction = config.curvature_correction;
      return std::make_unique<GradientProjectionLaw>(config.step, config.nullspace_step, options);
    }
    case ControlMethod::kExtendedJacobian:
      return std::make_unique<ExtendedJacobianLaw>(config.step, config.nullspace_step);
    case ControlMethod::kDither:
      return std::make_unique<DitheringLaw>(config.step, BuildDitherSettings(config.dither, timing));
  }
  throw std::invalid_argument("unknown control method");
}

}  // namespace dpc
