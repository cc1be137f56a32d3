// The controller part of the scenario validation: the control law's settings, the dither
// settings and the options beyond the paper (singularity damping, null-space criterion,
// curvature correction, prediction); ValidateControllerConfig.

#include "dpc/config/scenario_validation.h"

#include <fmt/format.h>

#include <cctype>
#include <string>

#include "dpc/config/field_checks.h"

namespace dpc {
namespace {

using field_checks::Fail;
using field_checks::kSampleCountTolerance;
using field_checks::RequireAtMost;
using field_checks::RequireFinite;
using field_checks::RequireNonNegative;
using field_checks::RequirePositive;

/// The name a user writes in the text file: "GP", "PINV", …
std::string MethodEnumName(ControlMethod method) {
  std::string name(MethodName(method));
  for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

// ---- Dither.

void ValidateDither(const DitherConfig& dither, double sample_rate_hz) {
  RequirePositive(dither.amplitude, "controller.dither.amplitude",
                  "the dither amplitude must be > 0 control units (typical 0.01 to 0.05)");
  if (dither.settle_samples < 0 || dither.settle_samples > kMaxDelaySamples) {
    Fail("controller.dither.settle_samples",
         fmt::format("{} is not in [0, {}]; settle_samples is a number of samples (0: the loop "
                     "delay)",
                     dither.settle_samples, kMaxDelaySamples));
  }
  RequirePositive(dither.reset_threshold, "controller.dither.reset_threshold",
                  "the reset threshold must be > 0 control units (typical 1)");
  const std::string reset_path = "controller.dither.reset_duration_s";
  RequireFinite(dither.reset_duration_s, reset_path,
                "the reset duration must be at least one sample period");
  const double samples = dither.reset_duration_s * sample_rate_hz;
  if (!(samples >= 1.0 - kSampleCountTolerance)) {
    Fail(reset_path, fmt::format("{} s is {:.6g} samples at {} Hz; a reset lasts at least one "
                                 "sample period ({} s)",
                                 dither.reset_duration_s, samples, sample_rate_hz,
                                 1.0 / sample_rate_hz));
  }
  if (samples > static_cast<double>(kMaxDelaySamples) * (1.0 + kSampleCountTolerance)) {
    Fail(reset_path, fmt::format("{} s is {:.6g} samples at {} Hz; at most {} samples",
                                 dither.reset_duration_s, samples, sample_rate_hz,
                                 kMaxDelaySamples));
  }
}

// ---- Options beyond the paper.

bool IsGradientProjection(ControlMethod method) {
  return method == ControlMethod::kGradientProjection ||
         method == ControlMethod::kThresholdedGradientProjection;
}

/// The options beyond the paper: singularity damping, range criterion, prediction.
void ValidateControllerOptions(const ControllerConfig& controller) {
  if (controller.singularity_damping) {
    const std::string path = "controller.singularity_damping";
    if (!IsGradientProjection(controller.method)) {
      Fail(path, fmt::format("applies to GP and GPT (the method is {}); DAMPED and RLS have "
                             "their own controller.damping",
                             MethodEnumName(controller.method)));
    }
    const SingularityDampingConfig& d = *controller.singularity_damping;
    RequirePositive(d.max_damping, path + ".max_damping",
                    "the largest damping lambda0 must be > 0 (typical 0.1 to 1)");
    RequireAtMost(d.max_damping, kMaxSingularityDamping, path + ".max_damping",
                  "the largest damping lambda0");
    RequirePositive(d.threshold, path + ".threshold",
                    "the singular value below which damping starts must be > 0 (typical 0.2 to 1)");
    RequireAtMost(d.threshold, kMaxSingularityDamping, path + ".threshold",
                  "the damping threshold");
  }
  // That some stage has a range is ValidateScenario's check: the controller alone does not
  // know the stages.
  if (controller.nullspace_criterion == NullspaceCriterion::kRange &&
      !IsGradientProjection(controller.method)) {
    Fail("controller.nullspace_criterion",
         fmt::format("RANGE applies to GP and GPT (the method is {})",
                     MethodEnumName(controller.method)));
  }
  if (controller.curvature_correction && !IsGradientProjection(controller.method)) {
    Fail("controller.curvature_correction",
         fmt::format("applies to GP and GPT (the method is {})", MethodEnumName(controller.method)));
  }
  if (controller.prediction) {
    const std::string path = "controller.prediction";
    if (controller.loop != LoopMode::kModel) {
      Fail(path, "needs loop MODEL: the prediction replaces the measured input SOP in the "
                 "model; in the MEASURED loop the error comes from the delayed output "
                 "polarimeter");
    }
    if (controller.method == ControlMethod::kDither) {
      Fail(path, "applies to the Jacobian laws; DITHER does not use the input SOP");
    }
    const PredictionConfig& q = *controller.prediction;
    RequirePositive(q.window_samples, path + ".window_samples",
                    "the predictor's window must be > 0 samples (typical 100 to 10000)");
    RequireAtMost(q.window_samples, kMaxPredictionSamples, path + ".window_samples",
                  "the predictor's window (samples)");
    if (q.horizon_samples) {
      RequireNonNegative(*q.horizon_samples, path + ".horizon_samples",
                         "the prediction horizon must be >= 0 samples (default: the loop delay)");
      RequireAtMost(*q.horizon_samples, kMaxPredictionSamples, path + ".horizon_samples",
                    "the prediction horizon (samples)");
    }
    if (q.lead_samples) {
      RequireNonNegative(*q.lead_samples, path + ".lead_samples",
                         "the lead must be >= 0 samples (default (1 - step)/step)");
      RequireAtMost(*q.lead_samples, kMaxPredictionSamples, path + ".lead_samples",
                    "the lead (samples)");
    }
  }
}

// ---- The controller as a whole.

/// Laws whose update is μ times a (generalized) inverse of the task: scale-free, the task error
/// contracts by (1 − μ) per update. The transpose and dithering laws scale with the device.
bool ScaleFreeLaw(ControlMethod method) {
  return method != ControlMethod::kTranspose && method != ControlMethod::kDither;
}

void ValidateController(const ControllerConfig& controller, int control_count,
                        const TargetConfig& target, const SimulationConfig& simulation) {
  RequirePositive(controller.step, "controller.step",
                  "the task step must be positive (typical 0.01 to 1)");
  RequireAtMost(controller.step, kMaxStep, "controller.step", "the task step");
  if (ScaleFreeLaw(controller.method) && !(controller.step < 2.0)) {
    // e[k+1] = (1 − μ) e[k] even with a perfect model: |1 − μ| ≥ 1.
    Fail("controller.step",
         fmt::format("{} is not < 2; with method {} the task error is multiplied by (1 - step) on "
                     "every update and the loop diverges (typical 0.01 to 1)",
                     controller.step, MethodEnumName(controller.method)));
  }
  RequireNonNegative(controller.nullspace_step, "controller.nullspace_step",
                     "the null-space step must be >= 0 (typical 0.01 to 1)");
  if (!(controller.nullspace_step < 2.0)) {
    Fail("controller.nullspace_step",
         fmt::format("{} is not < 2; the null-space part of φ is multiplied by (1 - nullspace_step) "
                     "on every update and diverges (typical 0.01 to 1)",
                     controller.nullspace_step));
  }
  RequireNonNegative(controller.threshold, "controller.threshold",
                     "the gpt threshold must be >= 0 control units (typical 1)");
  RequireAtMost(controller.threshold, kMaxStep, "controller.threshold", "the gpt threshold");
  RequireNonNegative(controller.damping, "controller.damping",
                     "the damping must be >= 0 (typical 1e-4 to 1e-2)");
  RequireAtMost(controller.damping, kMaxStep, "controller.damping", "the damping");
  if (controller.method == ControlMethod::kRegularizedLeastSquares && controller.damping == 0.0) {
    Fail("controller.damping",
         "0 with method RLS; regularized least squares needs damping > 0 (typical 1e-4 to 1e-2)");
  }
  const std::string tolerance_path = "controller.singular_value_tolerance";
  RequireFinite(controller.singular_value_tolerance, tolerance_path,
                "the relative tolerance must be in (0, 1) (typical 1e-12)");
  if (!(controller.singular_value_tolerance > 0.0 && controller.singular_value_tolerance < 1.0)) {
    Fail(tolerance_path, fmt::format("{} is not in (0, 1); the relative singular value "
                                     "tolerance is typically 1e-12 to 1e-6",
                                     controller.singular_value_tolerance));
  }
  RequireNonNegative(controller.activation_s, "controller.activation_s",
                     "the controller starts at >= 0 s");
  if (!(controller.activation_s < simulation.duration_s)) {
    Fail("controller.activation_s",
         fmt::format("{} s is not before the end of the run (simulation.duration_s = {} s); "
                     "the controller would never act",
                     controller.activation_s, simulation.duration_s));
  }
  const auto& phi = controller.initial_phi;
  if (!phi.empty() && phi.size() != static_cast<size_t>(control_count)) {
    Fail("controller.initial_phi",
         fmt::format("{} value(s) for {} control(s); give exactly one per control, or none for "
                     "all zeros",
                     phi.size(), control_count));
  }
  for (size_t j = 0; j < phi.size(); ++j) {
    RequireFinite(phi[j], fmt::format("controller.initial_phi[{}]", j),
                  "an initial control value must be finite");
  }
  if (controller.method == ControlMethod::kInverse || controller.method == ControlMethod::kDamped) {
    const bool point = target.kind == TargetConfig::Kind::kPoint;
    const int task_rows = point ? 3 : 1;
    if (control_count != task_rows) {
      Fail("controller.method",
           fmt::format("{} inverts a square task matrix: it needs {} control(s) for a {} target, "
                       "but the stages have {}; use PINV, RLS or GP",
                       MethodEnumName(controller.method), task_rows, point ? "point" : "set",
                       control_count));
    }
  }
  ValidateDither(controller.dither, simulation.sample_rate_hz);
  ValidateControllerOptions(controller);
}

}  // namespace

void ValidateControllerConfig(const ControllerConfig& controller, int control_count,
                              const TargetConfig& target, const SimulationConfig& simulation) {
  ValidateController(controller, control_count, target, simulation);
}

}  // namespace dpc
