#pragma once
// Chooses a control law by configuration.
//
//   method      law                                      uses
//   inverse     InverseJacobianLaw                       step
//   transpose   TransposeJacobianLaw                     step
//   damped      DampedJacobianLaw                        step, damping
//   pinv        PseudoInverseLaw                         step
//   rls         RegularizedLeastSquaresLaw               step, damping
//   gp          GradientProjectionLaw                    step, nullspace_step, singularity_*,
//                                                        range_aware
//   gpt         GradientProjectionLaw with threshold     the same and threshold
//   extended    ExtendedJacobianLaw                      step, nullspace_step
//   dither      DitheringLaw                             step, dither.*

#include <memory>
#include <optional>
#include <string_view>

#include "dpc/control/control_law.h"
#include "dpc/control/dithering_law.h"

namespace dpc {

enum class ControlMethod {
  kInverse,
  kTranspose,
  kDamped,
  kPseudoInverse,
  kRegularizedLeastSquares,
  kGradientProjection,
  kThresholdedGradientProjection,
  kExtendedJacobian,
  kDither,
};

/// "inverse", "transpose", "damped", "pinv", "rls", "gp", "gpt", "extended", "dither".
std::string_view MethodName(ControlMethod method);
/// The inverse of MethodName; nullopt for an unknown name.
std::optional<ControlMethod> ParseMethod(std::string_view name);
/// "inverse|transpose|damped|pinv|rls|gp|gpt|extended|dither".
std::string_view MethodNameList();

struct ControlLawConfig {
  ControlMethod method = ControlMethod::kGradientProjection;
  double step = 0.1;            ///< μ, task step (every law)
  double nullspace_step = 0.1;  ///< μ_N (gp, gpt, extended)
  double threshold = 1.0;       ///< |φ_i| above which gpt runs the null-space term
  double damping = 1e-3;        ///< λ (damped, rls)
  double singular_value_tolerance = 1e-12;  ///< relative, for J⁺
  DitherSettings dither;        ///< dither only
  /// gp, gpt: singularity-robust damping λ0 (0: off) and the σ_min below which it starts.
  double singularity_damping = 0.0;
  double singularity_threshold = 0.5;
  /// gp, gpt: the range criterion with saturate and re-solve (gradient_projection_law.h).
  bool range_aware = false;
  /// gp, gpt: one curvature correction step per update.
  bool curvature_correction = false;
};

/// Builds the configured law for `chain` and `target`. Throws std::invalid_argument when the
/// parameters are invalid or the method does not fit (inverse and damped need a square task:
/// 3 controls with a point target, or 1 control with a set target).
std::unique_ptr<ControlLaw> MakeControlLaw(const ControlLawConfig& config, int control_count,
                                           bool point_target);

}  // namespace dpc
