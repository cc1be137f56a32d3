#include "dpc/config/scenario_validation.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>

namespace dpc {
namespace {

/// Relative tolerance on "a whole number of samples" and "at least one sample".
constexpr double kSampleCountTolerance = 1e-6;

[[noreturn]] void Fail(const std::string& path, std::string message) {
  throw ScenarioError(path, std::move(message));
}

std::string FormatVector(const Vector3& v) {
  return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z());
}

/// The name a user writes in the text file: "GP", "PINV", …
std::string MethodEnumName(ControlMethod method) {
  std::string name(MethodName(method));
  for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

// ---- Scalars. `expected` says what the field should be, e.g. "the task step must be > 0".

void RequireFinite(double value, const std::string& path, std::string_view expected) {
  if (!std::isfinite(value)) {
    Fail(path, fmt::format("{} is not a finite number; {}", value, expected));
  }
}

void RequirePositive(double value, const std::string& path, std::string_view expected) {
  RequireFinite(value, path, expected);
  if (!(value > 0.0)) Fail(path, fmt::format("{} is not > 0; {}", value, expected));
}

void RequireNonNegative(double value, const std::string& path, std::string_view expected) {
  RequireFinite(value, path, expected);
  if (value < 0.0) Fail(path, fmt::format("{} is negative; {}", value, expected));
}

/// A finite value at most `max`; `what` names it in the message.
void RequireAtMost(double value, double max, const std::string& path, std::string_view what) {
  if (value > max) Fail(path, fmt::format("{} is above {:g}; {} must be at most that", value, max, what));
}

/// A rotation rate: finite, ≥ 0, and below π rad per sample.
void RequireRate(double rate_rad_per_s, double sample_rate_hz, const std::string& path) {
  RequireFinite(rate_rad_per_s, path, "a rotation rate must be finite and >= 0 rad/s");
  if (rate_rad_per_s < 0.0) {
    Fail(path, fmt::format("{} rad/s is negative; a rotation rate must be >= 0 (use the axis "
                           "direction to reverse)",
                           rate_rad_per_s));
  }
  const double rad_per_sample = rate_rad_per_s / sample_rate_hz;
  if (!(rad_per_sample < M_PI)) {
    Fail(path, fmt::format("{} rad/s at {} Hz: {:.6g} rad per sample exceeds π: the simulation "
                           "cannot resolve it; raise simulation.sample_rate_hz above {:.6g} Hz",
                           rate_rad_per_s, sample_rate_hz, rad_per_sample,
                           rate_rad_per_s / M_PI));
  }
}

// ---- Vectors: a non-finite component is reported at its own path (".s1", ".s2", ".s3").

void RequireFiniteVector(const Vector3& v, const std::string& path, std::string_view expected) {
  static constexpr const char* kComponents[3] = {"s1", "s2", "s3"};
  for (int k = 0; k < 3; ++k) RequireFinite(v[k], path + "." + kComponents[k], expected);
}

void RequireAxis(const Vector3& axis, const std::string& path) {
  RequireFiniteVector(axis, path, "an axis component must be finite");
  if (!(axis.norm() >= kMinAxisLength)) {
    Fail(path, fmt::format("zero-length axis {} (|axis| = {:.3g}); an axis needs a direction: "
                           "any vector with |axis| >= {:g} (it is normalized)",
                           FormatVector(axis), axis.norm(), kMinAxisLength));
  }
}

void RequireUnitStokes(const StokesVector& s, const std::string& path) {
  RequireFiniteVector(s, path, "a Stokes component must be finite");
  const double norm = s.norm();
  if (!(std::abs(norm - 1.0) <= kUnitNormTolerance)) {
    Fail(path, fmt::format("{} has |S| = {:.9g}; a fully polarized SOP is a unit Stokes vector "
                           "(|S| within {:g} of 1)",
                           FormatVector(s), norm, kUnitNormTolerance));
  }
}

// ---- Stages.

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

// ---- Input.

void ValidateDisturbance(const DisturbanceConfig& d, double sample_rate_hz,
                         const std::string& path) {
  switch (d.kind) {
    case DisturbanceConfig::Kind::kPaperScrambler: {
      const std::string p = path + ".paper_scrambler";
      RequireRate(d.rate_rad_per_s, sample_rate_hz, p + ".rate_rad_per_s");
      RequireNonNegative(d.kick_rms_ratio, p + ".kick_rms_ratio",
                         "the kick rms ratio must be >= 0 (the paper: 1)");
      RequireAxis(d.axis, p + ".rotation_axis_vector");
      RequireAxis(d.kick_axis, p + ".kick_axis_vector");
      return;
    }
    case DisturbanceConfig::Kind::kRandomWalk:
      RequireNonNegative(d.diffusion_rad_per_sqrt_s,
                         path + ".random_walk.diffusion_rad_per_sqrt_s",
                         "the diffusion constant must be >= 0 rad/√s");
      return;
    case DisturbanceConfig::Kind::kConstantRotation: {
      const std::string p = path + ".constant_rotation";
      RequireRate(d.rate_rad_per_s, sample_rate_hz, p + ".rate_rad_per_s");
      RequireAxis(d.axis, p + ".axis_vector");
      return;
    }
    case DisturbanceConfig::Kind::kTransientBurst: {
      const std::string p = path + ".transient_burst";
      RequireNonNegative(d.start_s, p + ".start_s", "the first burst must start at >= 0 s");
      RequirePositive(d.duration_s, p + ".duration_s",
                      "a burst must last > 0 s (lightning: tens of µs)");
      RequireRate(d.rate_rad_per_s, sample_rate_hz, p + ".rate_rad_per_s");
      const std::string period_path = p + ".period_s";
      RequireNonNegative(d.period_s, period_path,
                         "period_s is 0 (a single burst) or >= duration_s");
      if (d.period_s != 0.0 && d.period_s < d.duration_s) {
        Fail(period_path, fmt::format("{} s is shorter than duration_s ({} s); period_s is 0 "
                                      "(a single burst) or >= duration_s",
                                      d.period_s, d.duration_s));
      }
      if (!d.random_axis) RequireAxis(d.axis, p + ".axis_vector");
      return;
    }
  }
  Fail(path, "unknown disturbance kind");
}

void ValidateInput(const InputConfig& input, double sample_rate_hz) {
  RequireUnitStokes(input.initial_sop, "input.initial_sop");
  if (input.disturbances.size() > static_cast<size_t>(kMaxDisturbances)) {
    Fail("input.disturbances", fmt::format("{} disturbances; at most {}",
                                           input.disturbances.size(), kMaxDisturbances));
  }
  for (size_t k = 0; k < input.disturbances.size(); ++k) {
    ValidateDisturbance(input.disturbances[k], sample_rate_hz,
                        fmt::format("input.disturbances[{}]", k));
  }
}

// ---- Target.

void ValidateTarget(const TargetConfig& target) {
  switch (target.kind) {
    case TargetConfig::Kind::kPoint: RequireUnitStokes(target.point, "target.point"); return;
    case TargetConfig::Kind::kSet: {
      RequireFiniteVector(target.normal, "target.set.normal", "a normal component must be finite");
      const double norm = target.normal.norm();
      if (!(norm >= kMinAxisLength)) {
        Fail("target.set.normal",
             fmt::format("zero-length normal {}; n·S = offset needs a direction: |normal| >= {:g}",
                         FormatVector(target.normal), kMinAxisLength));
      }
      RequireFinite(target.offset, "target.set.offset", "the set offset must be finite");
      const double ratio = std::abs(target.offset) / norm;
      if (!(ratio < 1.0)) {
        Fail("target.set.offset",
             fmt::format("|offset|/|normal| = {:.6g} is not < 1: n·S = offset has no circle on "
                         "the sphere (= 1 is a single point: use a point target)",
                         ratio));
      }
      return;
    }
  }
  Fail("target", "unknown target kind");
}

// ---- Controller.

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

void ValidateController(const ControllerConfig& controller, int control_count,
                        const TargetConfig& target, const SimulationConfig& simulation) {
  RequirePositive(controller.step, "controller.step",
                  "the task step must be positive (typical 0.01 to 1)");
  RequireNonNegative(controller.nullspace_step, "controller.nullspace_step",
                     "the null-space step must be >= 0 (typical 0.01 to 1)");
  RequireNonNegative(controller.threshold, "controller.threshold",
                     "the gpt threshold must be >= 0 control units (typical 1)");
  RequireNonNegative(controller.damping, "controller.damping",
                     "the damping must be >= 0 (typical 1e-4 to 1e-2)");
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

// ---- Simulation.

void ValidateSimulation(const SimulationConfig& sim) {
  const double fs = sim.sample_rate_hz;
  RequirePositive(fs, "simulation.sample_rate_hz",
                  "the sample rate must be positive (the paper: 50e6 Hz)");
  if (fs > kMaxSampleRateHz) {
    Fail("simulation.sample_rate_hz",
         fmt::format("{} Hz is above {:g} Hz; the sample rate must be at most that", fs,
                     kMaxSampleRateHz));
  }
  const double dt = 1.0 / fs;

  const std::string delay_path = "simulation.delay_s";
  RequireFinite(sim.delay_s, delay_path,
                "the loop delay must be a whole number (>= 1) of sample periods");
  const double delay_samples = sim.delay_s * fs;
  if (!(delay_samples >= 1.0 - kSampleCountTolerance)) {
    Fail(delay_path, fmt::format("{} s is {:.6g} samples at {} Hz, less than one sample period "
                                 "({} s); a command cannot act on the sample it was computed "
                                 "from",
                                 sim.delay_s, delay_samples, fs, dt));
  }
  if (delay_samples > static_cast<double>(kMaxDelaySamples) * (1.0 + kSampleCountTolerance)) {
    Fail(delay_path, fmt::format("{} s is {:.6g} samples at {} Hz; the loop delay is at most {} "
                                 "samples",
                                 sim.delay_s, delay_samples, fs, kMaxDelaySamples));
  }
  const double whole = std::round(delay_samples);
  if (std::abs(delay_samples - whole) > kSampleCountTolerance * whole) {
    Fail(delay_path, fmt::format("delay_s·sample_rate_hz = {}·{} = {:.9g} samples is not a whole "
                                 "number; use a multiple of the sample period {} s (the nearest "
                                 "is {} s)",
                                 sim.delay_s, fs, delay_samples, dt, whole * dt));
  }

  const std::string duration_path = "simulation.duration_s";
  RequirePositive(sim.duration_s, duration_path, "the run must last > 0 s");
  const double total = std::round(sim.duration_s * fs);
  if (!(total >= 1.0)) {
    Fail(duration_path, fmt::format("{} s is {:.6g} samples at {} Hz; a run needs at least one "
                                    "sample",
                                    sim.duration_s, sim.duration_s * fs, fs));
  }
  if (total > static_cast<double>(kMaxTotalSamples)) {
    Fail(duration_path, fmt::format("oversized run: {} s at {} Hz is {:.6g} samples; at most "
                                    "{:g}",
                                    sim.duration_s, fs, total,
                                    static_cast<double>(kMaxTotalSamples)));
  }

  const std::string noise_path = "simulation.polarimeter_noise_deg";
  RequireNonNegative(sim.polarimeter_noise_deg, noise_path,
                     "the polarimeter noise must be in [0, 180] degrees (0: ideal)");
  if (sim.polarimeter_noise_deg > 180.0) {
    Fail(noise_path, fmt::format("{} deg is above 180 deg; the polarimeter noise must be in "
                                 "[0, 180] degrees (0: ideal)",
                                 sim.polarimeter_noise_deg));
  }
  const std::string lock_path = "simulation.lock_threshold_deg";
  RequirePositive(sim.lock_threshold_deg, lock_path,
                  "the lock threshold must be in (0, 180] degrees (typical 10)");
  if (sim.lock_threshold_deg > 180.0) {
    Fail(lock_path, fmt::format("{} deg is above 180 deg; the lock threshold must be in (0, 180] "
                                "degrees (typical 10)",
                                sim.lock_threshold_deg));
  }
  if (sim.settle_samples < 0 || sim.settle_samples > TotalSamples(sim)) {
    Fail("simulation.settle_samples",
         fmt::format("{} is outside [0, {}] (the run's samples); the lock-in transient left out "
                     "of the error statistics is a number of samples",
                     sim.settle_samples, TotalSamples(sim)));
  }
  if (sim.statistics_start_s) {
    const std::string start_path = "simulation.statistics_start_s";
    RequireNonNegative(*sim.statistics_start_s, start_path,
                       "statistics start at >= 0 s, before the end of the run");
    if (!(*sim.statistics_start_s < sim.duration_s)) {
      Fail(start_path, fmt::format("{} s is not before the end of the run (duration_s = {} s); "
                                   "no sample would count",
                                   *sim.statistics_start_s, sim.duration_s));
    }
  }
}

/// round(x), saturated to [0, INT64_MAX]; 0 for NaN.
int64_t SaturatingRound(double x) {
  if (!(x > 0.0)) return 0;
  // 2^63 is exactly representable; every double below it converts safely.
  if (x >= 9223372036854775808.0) return std::numeric_limits<int64_t>::max();
  return std::llround(x);
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

int64_t DelaySamples(const SimulationConfig& simulation) {
  return SaturatingRound(simulation.delay_s * simulation.sample_rate_hz);
}

int64_t TotalSamples(const SimulationConfig& simulation) {
  return SaturatingRound(simulation.duration_s * simulation.sample_rate_hz);
}

void ValidateDeviceStages(const std::vector<StageConfig>& stages) { ValidateStages(stages); }

void ValidateTargetConfig(const TargetConfig& target) { ValidateTarget(target); }

void ValidateControllerConfig(const ControllerConfig& controller, int control_count,
                              const TargetConfig& target, const SimulationConfig& simulation) {
  ValidateController(controller, control_count, target, simulation);
}

void ValidateScenario(const ScenarioConfig& scenario) {
  ValidateSimulation(scenario.simulation);
  ValidateStages(scenario.stages);
  ValidateInput(scenario.input, scenario.simulation.sample_rate_hz);
  ValidateTarget(scenario.target);
  ValidateController(scenario.controller, ScenarioControlCount(scenario.stages), scenario.target,
                     scenario.simulation);
  if (scenario.controller.nullspace_criterion == NullspaceCriterion::kRange) {
    bool any_range = false;
    for (const StageConfig& stage : scenario.stages) {
      any_range = any_range || stage.range || (stage.retardance.controlled && stage.retardance.range) ||
                  (stage.orientation.controlled && stage.orientation.range);
    }
    if (!any_range) {
      Fail("controller.nullspace_criterion",
           "RANGE keeps the controls inside their ranges, but no stage has a range; give "
           "stages[i].range (e.g. { min: -1 max: 1 })");
    }
  }
}

}  // namespace dpc
