#pragma once
// Command-line flags that override fields of a scenario (`dpc sim`, `dpc sweep`).
//
//   --stages-axes 3131      stages ← fixed-axis stages S3, S1, S3, S1 with θ = π·φ (the light
//                           meets the first character first); clears controller.initial_phi
//   --method gp             controller.method (inverse|transpose|damped|pinv|rls|gp|gpt|…)
//   --step, --nullspace-step, --threshold                  controller.*
//   --damping X             damped, rls: controller.damping (λ); gp, gpt: singularity-robust
//                           damping on with controller.singularity_damping.max_damping = X
//   --damping-threshold E   gp, gpt: controller.singularity_damping.threshold (turns it on)
//   --predict / --no-predict   controller.prediction on (defaults) / off
//   --predict-window N      controller.prediction.window_samples (turns prediction on)
//   --correct               controller.curvature_correction (gp, gpt)
//   --range R               every control's range [−R, R], and for gp / gpt the range criterion
//                           (controller.nullspace_criterion RANGE, saturate and re-solve)
//   --target-point s1,s2,s3 target.point
//   --target-set n1,n2,n3[,c]   target.set: n·S = c (c = 0 if omitted), e.g. 0,0,1 for s3 = 0
//   --target-linear         target.set s3 = 0: any linear polarization (as `dpc target --linear`)
//   --loop model|measured   controller.loop
//   --activation-s          controller.activation_s
//   --rate-rad-per-s        rate of every paper_scrambler and constant_rotation disturbance;
//                           adds a paper scrambler if the input has neither
//   --static                the input SOP holds still (removes every disturbance)
//   --duration-s, --delay-s, --sample-rate-hz, --seed, --noise-deg, --lock-threshold-deg,
//   --statistics-from-s, --settle-samples   simulation.*
//   --operating-temperature-c, --operating-wavelength-nm   the operating point of every map
//                           keyed by temperature / wavelength (tables_by_condition)
//
// Overrides are applied to the plain ScenarioConfig before validation; when validation then
// rejects a field that a flag set, the message names the flag as well.

#include <CLI/CLI.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"

namespace dpc::cli {

struct ScenarioOverrides {
  std::optional<std::string> stages_axes;
  std::optional<std::string> method;
  std::optional<double> step, nullspace_step, threshold, damping, activation_s;
  std::optional<double> damping_threshold;
  bool predict = false, no_predict = false, correct = false, target_linear = false;
  std::optional<double> predict_window;
  std::optional<double> range;
  std::vector<double> target_point, target_set;
  std::optional<std::string> loop;
  std::optional<double> rate_rad_per_s;
  bool static_input = false;
  std::optional<double> duration_s, delay_s, sample_rate_hz, noise_deg, lock_threshold_deg,
      statistics_from_s;
  std::optional<uint64_t> seed;
  std::optional<int64_t> settle_samples;
  std::optional<double> operating_temperature_c, operating_wavelength_nm;

  /// Registers the flags on `app`.
  void AddTo(CLI::App& app);

  /// Applies the set flags to `scenario`. Throws ScenarioError for values that cannot even be
  /// stored (an unknown method or loop name, bad axes, --static with --rate-rad-per-s).
  void Apply(ScenarioConfig* scenario) const;

  /// The flags given that the scenario's law does not use (e.g. --threshold with gp), one line
  /// each, for the command to warn about: the run goes on, but not as the flag asked.
  std::vector<std::string> IgnoredFlags(const ScenarioConfig& scenario) const;

  /// The flag that set the scenario field at `field_path` (e.g. "--step" for
  /// "controller.step"), if one did.
  std::optional<std::string> FlagForField(const std::string& field_path) const;

 private:
  mutable std::map<std::string, std::string> field_to_flag_;
};

}  // namespace dpc::cli
