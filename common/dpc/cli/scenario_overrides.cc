#include "dpc/cli/scenario_overrides.h"

#include <fmt/format.h>

#include <tuple>

#include "dpc/cli/command_line.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_error.h"

namespace dpc::cli {

void ScenarioOverrides::AddTo(CLI::App& app) {
  app.add_option("--stages-axes", stages_axes,
                 "Replace the device by fixed-axis stages along these axes, in light order, "
                 "theta = pi*phi (e.g. 131, 3131)");
  app.add_option("--method", method, "Control law: inverse|transpose|damped|pinv|rls|gp|gpt|"
                                     "extended|dither");
  app.add_option("--step", step, "Task step mu");
  app.add_option("--nullspace-step", nullspace_step, "Null-space step mu_N (gp, gpt, extended)");
  app.add_option("--threshold", threshold, "|phi_i| above which gpt runs the null-space term");
  app.add_option("--damping", damping,
                 "Damping: lambda of damped and rls; for gp and gpt the largest "
                 "singularity-robust damping lambda0 (turns it on)");
  app.add_option("--damping-threshold", damping_threshold,
                 "gp, gpt: singular value below which the damping starts (default 0.5)");
  app.add_flag("--predict", predict,
               "Delay compensation: aim at the input SOP predicted across the loop delay");
  app.add_flag("--no-predict", no_predict, "No delay compensation (even if the scenario has it)");
  app.add_option("--predict-window", predict_window,
                 "Samples of history the predictor fits (default 1000; turns prediction on)");
  app.add_flag("--correct", correct,
               "gp, gpt: one curvature correction step per update (exact tracking at high rates)");
  app.add_option("--range", range,
                 "Every control in [-R, R]; gp and gpt keep inside with the range criterion "
                 "and saturate-and-re-solve");
  app.add_option("--target-point", target_point, "Point target s1,s2,s3 (a unit Stokes vector)")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--target-set", target_set,
                 "1-D target n.S = c as n1,n2,n3[,c] (e.g. 0,0,1 for s3 = 0: any linear "
                 "polarization)")
      ->delimiter(',')
      ->expected(3, 4);
  app.add_flag("--target-linear", target_linear,
               "1-D target s3 = 0: any linear polarization (the same as --target-set 0,0,1)");
  app.add_option("--loop", loop, "Loop mode: model (S_out from the model) or measured");
  app.add_option("--activation-s", activation_s, "Control starts at this time (s)");
  app.add_option("--rate-rad-per-s", rate_rad_per_s,
                 "Input rotation rate of the scrambler / constant rotation (rad/s)");
  app.add_flag("--static", static_input, "Hold the input SOP still (no disturbances)");
  app.add_option("--operating-temperature-c", operating_temperature_c,
                 "The operating point of every map keyed by temperature (tables by condition, e.g. from "
                 "dpc calibrate --temperatures-c)");
  app.add_option("--operating-wavelength-nm", operating_wavelength_nm,
                 "The operating point of every map keyed by wavelength (dpc calibrate --wavelengths-nm)");
  app.add_option("--duration-s", duration_s, "Simulated time (s)");
  app.add_option("--delay-s", delay_s, "Loop delay (s), a whole number of samples");
  app.add_option("--sample-rate-hz", sample_rate_hz, "Sample rate (Hz)");
  app.add_option("--seed", seed, "Random seed (0 … 2^64 − 1)")->check(UnsignedInteger());
  app.add_option("--noise-deg", noise_deg, "Polarimeter noise sigma per tangent axis (deg)");
  app.add_option("--lock-threshold-deg", lock_threshold_deg,
                 "Lock: the error stays below this (deg); default 10");
  app.add_option("--statistics-from-s", statistics_from_s,
                 "Error statistics from this time (s); default: settle samples after the first "
                 "lock");
  app.add_option("--settle-samples", settle_samples,
                 "Samples after the first lock left out of the error statistics (default 1000)");
}

void ScenarioOverrides::Apply(ScenarioConfig* s) const {
  field_to_flag_.clear();
  const auto set = [this](auto& field, const auto& value, const char* path, const char* flag) {
    if (value) {
      field = *value;
      field_to_flag_[path] = flag;
    }
  };
  if (static_input && rate_rad_per_s) {
    throw ScenarioError("--static", "contradicts --rate-rad-per-s: a static input has no rate");
  }
  if (stages_axes) {
    try {
      s->stages = StagesFromAxes(*stages_axes);
    } catch (const std::invalid_argument& e) {
      throw ScenarioError("--stages-axes", e.what());
    }
    s->controller.initial_phi.clear();
    field_to_flag_["stages"] = "--stages-axes";
  }
  if (method) {
    const auto parsed = ParseMethod(*method);
    if (!parsed) {
      throw ScenarioError("--method", fmt::format("unknown method \"{}\"; use one of {}", *method,
                                                  MethodNameList()));
    }
    s->controller.method = *parsed;
    field_to_flag_["controller.method"] = "--method";
  }
  if (loop) {
    if (*loop == "model") {
      s->controller.loop = LoopMode::kModel;
    } else if (*loop == "measured") {
      s->controller.loop = LoopMode::kMeasured;
    } else {
      throw ScenarioError("--loop", fmt::format("unknown loop mode \"{}\"; use model or measured",
                                                *loop));
    }
    field_to_flag_["controller.loop"] = "--loop";
  }
  set(s->controller.step, step, "controller.step", "--step");
  set(s->controller.nullspace_step, nullspace_step, "controller.nullspace_step",
      "--nullspace-step");
  set(s->controller.threshold, threshold, "controller.threshold", "--threshold");
  const bool gradient_projection =
      s->controller.method == ControlMethod::kGradientProjection ||
      s->controller.method == ControlMethod::kThresholdedGradientProjection;
  if (damping && !gradient_projection) {
    set(s->controller.damping, damping, "controller.damping", "--damping");
  } else if (damping || damping_threshold) {
    SingularityDampingConfig config = s->controller.singularity_damping.value_or(
        SingularityDampingConfig{});
    if (damping) config.max_damping = *damping;
    if (damping_threshold) config.threshold = *damping_threshold;
    s->controller.singularity_damping = config;
    if (damping) field_to_flag_["controller.singularity_damping.max_damping"] = "--damping";
    if (damping_threshold) {
      field_to_flag_["controller.singularity_damping.threshold"] = "--damping-threshold";
    }
  }
  if (predict && no_predict) {
    throw ScenarioError("--predict", "contradicts --no-predict");
  }
  if (no_predict && predict_window) {
    throw ScenarioError("--no-predict", "contradicts --predict-window");
  }
  if (no_predict) s->controller.prediction.reset();
  if (predict || predict_window) {
    PredictionConfig config = s->controller.prediction.value_or(PredictionConfig{});
    if (predict_window) config.window_samples = *predict_window;
    s->controller.prediction = config;
    if (predict_window) {
      field_to_flag_["controller.prediction.window_samples"] = "--predict-window";
    } else {
      field_to_flag_["controller.prediction"] = "--predict";
    }
  }
  if (correct) {
    s->controller.curvature_correction = true;
    field_to_flag_["controller.curvature_correction"] = "--correct";
  }
  if (range) {
    const ControlRange r{-*range, *range};
    for (size_t i = 0; i < s->stages.size(); ++i) {
      StageConfig& stage = s->stages[i];
      if (stage.kind == StageConfig::Kind::kFixedAxis) {
        stage.range = r;
        field_to_flag_[fmt::format("stages[{}].range", i)] = "--range";
      } else {
        if (stage.retardance.controlled) stage.retardance.range = r;
        if (stage.orientation.controlled) stage.orientation.range = r;
        field_to_flag_[fmt::format("stages[{}].adjustable_axis", i)] = "--range";
      }
    }
    if (gradient_projection) {
      s->controller.nullspace_criterion = NullspaceCriterion::kRange;
      field_to_flag_["controller.nullspace_criterion"] = "--range";
    }
  }
  for (const auto& [point, condition, flag] :
       {std::tuple{operating_temperature_c, ControlMapConfig::Condition::kTemperatureC, "--operating-temperature-c"},
        std::tuple{operating_wavelength_nm, ControlMapConfig::Condition::kWavelengthNm, "--operating-wavelength-nm"}}) {
    if (!point) continue;
    int keyed = 0;
    const auto apply = [&](ControlMapConfig& map, const std::string& path) {
      if (map.kind != ControlMapConfig::Kind::kTablesByCondition || map.condition != condition) return;
      map.operating_point = *point;
      field_to_flag_[fmt::format("{}.tables_by_condition.operating_{}", path, ConditionKeyName(condition))] = flag;
      ++keyed;
    };
    for (size_t i = 0; i < s->stages.size(); ++i) {
      StageConfig& stage = s->stages[i];
      apply(stage.map, fmt::format("stages[{}].map", i));
      if (stage.retardance.controlled) {
        apply(stage.retardance.map, fmt::format("stages[{}].adjustable_axis.retardance.controlled.map", i));
      }
      if (stage.orientation.controlled) {
        apply(stage.orientation.map, fmt::format("stages[{}].adjustable_axis.orientation.controlled.map", i));
      }
    }
    if (keyed == 0) {
      throw ScenarioError(flag, fmt::format("no map of the scenario is keyed by {} (tables_by_condition with "
                                            "operating_{})",
                                            ConditionNoun(condition), ConditionKeyName(condition)));
    }
  }
  if (static_cast<int>(!target_point.empty()) + static_cast<int>(!target_set.empty()) +
          static_cast<int>(target_linear) > 1) {
    throw ScenarioError(!target_point.empty() ? "--target-point" : "--target-set",
                        "give one of --target-point, --target-set, --target-linear");
  }
  if (target_linear) {
    s->target.kind = TargetConfig::Kind::kSet;
    s->target.normal = Vector3::UnitZ();
    s->target.offset = 0.0;
    field_to_flag_["target.set"] = "--target-linear";
  }
  if (!target_point.empty()) {
    s->target.kind = TargetConfig::Kind::kPoint;
    s->target.point = StokesVector(target_point[0], target_point[1], target_point[2]);
    field_to_flag_["target.point"] = "--target-point";
  }
  if (!target_set.empty()) {
    s->target.kind = TargetConfig::Kind::kSet;
    s->target.normal = Vector3(target_set[0], target_set[1], target_set[2]);
    s->target.offset = target_set.size() > 3 ? target_set[3] : 0.0;
    field_to_flag_["target.set"] = "--target-set";
  }
  set(s->controller.activation_s, activation_s, "controller.activation_s", "--activation-s");
  set(s->simulation.duration_s, duration_s, "simulation.duration_s", "--duration-s");
  set(s->simulation.delay_s, delay_s, "simulation.delay_s", "--delay-s");
  set(s->simulation.sample_rate_hz, sample_rate_hz, "simulation.sample_rate_hz",
      "--sample-rate-hz");
  set(s->simulation.seed, seed, "simulation.seed", "--seed");
  set(s->simulation.settle_samples, settle_samples, "simulation.settle_samples", "--settle-samples");
  set(s->simulation.polarimeter_noise_deg, noise_deg, "simulation.polarimeter_noise_deg",
      "--noise-deg");
  set(s->simulation.lock_threshold_deg, lock_threshold_deg, "simulation.lock_threshold_deg",
      "--lock-threshold-deg");
  if (statistics_from_s) {
    s->simulation.statistics_start_s = *statistics_from_s;
    field_to_flag_["simulation.statistics_start_s"] = "--statistics-from-s";
  }
  if (static_input) s->input.disturbances.clear();
  if (rate_rad_per_s) {
    bool found = false;
    auto& disturbances = s->input.disturbances;
    for (size_t i = 0; i < disturbances.size(); ++i) {
      auto& d = disturbances[i];
      if (d.kind == DisturbanceConfig::Kind::kPaperScrambler ||
          d.kind == DisturbanceConfig::Kind::kConstantRotation) {
        d.rate_rad_per_s = *rate_rad_per_s;
        const char* kind =
            d.kind == DisturbanceConfig::Kind::kPaperScrambler ? "paper_scrambler" : "constant_rotation";
        field_to_flag_[fmt::format("input.disturbances[{}].{}.rate_rad_per_s", i, kind)] =
            "--rate-rad-per-s";
        found = true;
      }
    }
    if (!found) {
      DisturbanceConfig scrambler;
      scrambler.rate_rad_per_s = *rate_rad_per_s;
      disturbances.push_back(scrambler);
      field_to_flag_[fmt::format("input.disturbances[{}].paper_scrambler.rate_rad_per_s",
                                 disturbances.size() - 1)] = "--rate-rad-per-s";
    }
  }
}

std::vector<std::string> ScenarioOverrides::IgnoredFlags(const ScenarioConfig& scenario) const {
  const ControllerConfig& c = scenario.controller;
  const std::string_view method = MethodName(c.method);
  const bool gradient_projection = c.method == ControlMethod::kGradientProjection ||
                                   c.method == ControlMethod::kThresholdedGradientProjection;
  std::vector<std::string> ignored;
  if (threshold && c.method != ControlMethod::kThresholdedGradientProjection) {
    ignored.push_back(fmt::format("--threshold applies to gpt; method {} ignores it", method));
  }
  if (nullspace_step && !gradient_projection && c.method != ControlMethod::kExtendedJacobian) {
    ignored.push_back(
        fmt::format("--nullspace-step applies to gp, gpt and extended; method {} ignores it", method));
  }
  if (damping && !gradient_projection && c.method != ControlMethod::kDamped &&
      c.method != ControlMethod::kRegularizedLeastSquares) {
    ignored.push_back(
        fmt::format("--damping applies to damped, rls, gp and gpt; method {} ignores it", method));
  }
  return ignored;
}

std::optional<std::string> ScenarioOverrides::FlagForField(const std::string& field_path) const {
  // A path names the flag's field or something inside it (e.g. stages[2].axis_vector).
  for (const auto& [field, flag] : field_to_flag_) {
    if (field_path == field || field_path.rfind(field + ".", 0) == 0 ||
        field_path.rfind(field + "[", 0) == 0) {
      return flag;
    }
  }
  return std::nullopt;
}

}  // namespace dpc::cli
