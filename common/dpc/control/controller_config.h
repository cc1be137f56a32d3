#pragma once
// The controller's settings (scenario.proto Controller), with their defaults written once: the
// paper's controller, gradient projection with step 0.1 in the model loop, activated at 2 ms.
// The scenario (config/scenario_config.h), the control-law factory, the simulator and the DDS
// controller all read this one struct.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace dpc {

/// The control laws (control_law_factory.h says which setting each one uses).
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

/// Which S_out enters the task error (control_problem.h).
enum class LoopMode {
  kModel,     ///< S_out = f(φ; S_in measured): the output polarimeter is optional (the paper)
  kMeasured,  ///< the output polarimeter's reading, which lags the command by the loop delay
};

/// scenario.proto Dither (the dithering baseline's own settings).
struct DitherConfig {
  double amplitude = 0.02;
  /// Samples to wait after each probe; 0 = the loop delay in samples.
  int64_t settle_samples = 0;
  double reset_threshold = 1.0;
  double reset_duration_s = 1e-6;
};

/// scenario.proto SingularityDamping: damped J⁺ near singularities (gp, gpt):
/// λ² = max_damping²·(1 − (σ_min/threshold)²) below σ_min = threshold, 0 above.
struct SingularityDampingConfig {
  double max_damping = 0.25;  ///< λ0
  double threshold = 0.5;     ///< ε
};

/// scenario.proto NullspaceCriterion (gp, gpt).
enum class NullspaceCriterion {
  kMinimumNorm,  ///< H = ½‖φ‖² (the paper)
  kRange,        ///< H = Σ h²(x²/2 + x⁸/8), x in range units, with saturate and re-solve
};

/// scenario.proto Prediction: delay compensation (delay_compensator.h). Model loop only.
struct PredictionConfig {
  double window_samples = 1000;          ///< the predictor's memory, samples
  std::optional<double> horizon_samples; ///< unset: the loop delay in samples
  std::optional<double> lead_samples;    ///< unset: (1 − step)/step, the integrator's lag
};

/// scenario.proto Controller.
struct ControllerConfig {
  ControlMethod method = ControlMethod::kGradientProjection;
  double step = 0.1;                       ///< μ, the task step (every law)
  double nullspace_step = 0.1;             ///< μ_N (gp, gpt, extended)
  double threshold = 1.0;                  ///< |φ_i| above which gpt runs the null-space term
  double damping = 1e-3;                   ///< λ (damped, rls)
  double singular_value_tolerance = 1e-12; ///< relative, for J⁺
  LoopMode loop = LoopMode::kModel;
  double activation_s = 2e-3;
  /// φ before activation, one per control; empty = all zero.
  std::vector<double> initial_phi;
  DitherConfig dither;
  std::optional<SingularityDampingConfig> singularity_damping;  ///< unset: off
  NullspaceCriterion nullspace_criterion = NullspaceCriterion::kMinimumNorm;
  std::optional<PredictionConfig> prediction;                   ///< unset: off
  bool curvature_correction = false;  ///< gp, gpt: one correction step for the curvature
};

/// The loop's timing as a law needs it (the dithering law counts samples).
struct LawTiming {
  double sample_rate_hz = 50e6;
  int64_t delay_samples = 50;   ///< the loop delay in samples (≥ 1)
};

}  // namespace dpc
