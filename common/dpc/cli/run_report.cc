#include "dpc/cli/run_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "dpc/config/scenario_validation.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/sim/batch_simulator.h"

namespace dpc::cli {
namespace {

nlohmann::ordered_json Number(double value) {
  if (!std::isfinite(value)) return nullptr;
  return value;
}

nlohmann::ordered_json Optional(const std::optional<double>& value) {
  return value ? Number(*value) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json Array(const std::vector<double>& values) {
  nlohmann::ordered_json array = nlohmann::ordered_json::array();
  for (double v : values) array.push_back(Number(v));
  return array;
}

std::string FormatOptional(const std::optional<double>& value, double scale, const char* unit) {
  return value ? fmt::format("{:.4g} {}", *value * scale, unit) : "never";
}

std::string FormatList(const std::vector<double>& values) {
  std::string text;
  for (double v : values) text += fmt::format("{}{:+.3f}", text.empty() ? "" : " ", v);
  return text;
}

/// "prediction (window 1000 samples), damping λ0 0.25 below σ 0.5, range criterion, curvature
/// correction", or "" for the paper's controller.
std::string OptionsText(const ControllerConfig& c) {
  std::string text;
  const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
  if (c.prediction) add(fmt::format("prediction (window {:g} samples)", c.prediction->window_samples));
  if (c.singularity_damping) {
    add(fmt::format("damping λ0 {:g} below σ {:g}", c.singularity_damping->max_damping,
                    c.singularity_damping->threshold));
  }
  if (c.nullspace_criterion == NullspaceCriterion::kRange) add("range criterion");
  if (c.curvature_correction) add("curvature correction");
  return text;
}

}  // namespace

double InputRateRadPerS(const ScenarioConfig& scenario) {
  for (const auto& d : scenario.input.disturbances) {
    if (d.kind == DisturbanceConfig::Kind::kPaperScrambler ||
        d.kind == DisturbanceConfig::Kind::kConstantRotation) {
      return d.rate_rad_per_s;
    }
  }
  return NAN;
}

RunDescription DescribeRun(const ScenarioConfig& scenario, const WaveplateChain& chain, const Target& target,
                           std::string loop_kernel) {
  return RunDescription{scenario, chain.Describe(), chain.control_count(), target.Describe(),
                        DelaySamples(scenario.simulation), std::move(loop_kernel)};
}

RunDescription DescribeRun(const ClosedLoopSimulator& simulator) {
  return DescribeRun(simulator.scenario(), simulator.chain(), simulator.target(),
                     simulator.uses_fast_path() ? "fast" : "general");
}

nlohmann::ordered_json RunSettingsJson(const RunDescription& run) {
  const ScenarioConfig& s = run.scenario;
  nlohmann::ordered_json j;
  j["scenario"] = s.name;
  j["stages"] = run.device;
  j["controls"] = run.controls;
  j["method"] = std::string(MethodName(s.controller.method));
  j["loop"] = s.controller.loop == LoopMode::kModel ? "model" : "measured";
  j["step"] = s.controller.step;
  j["nullspace_step"] = s.controller.nullspace_step;
  j["prediction"] = s.controller.prediction.has_value();
  j["singularity_damping"] = s.controller.singularity_damping
                                 ? Number(s.controller.singularity_damping->max_damping)
                                 : nlohmann::ordered_json(nullptr);
  j["range_criterion"] = s.controller.nullspace_criterion == NullspaceCriterion::kRange;
  j["curvature_correction"] = s.controller.curvature_correction;
  j["target"] = run.target;
  j["rate_rad_per_s"] = Number(InputRateRadPerS(s));
  j["sample_rate_hz"] = s.simulation.sample_rate_hz;
  j["delay_s"] = s.simulation.delay_s;
  j["delay_samples"] = run.delay_samples;
  j["duration_s"] = s.simulation.duration_s;
  j["activation_s"] = s.controller.activation_s;
  j["polarimeter_noise_deg"] = s.simulation.polarimeter_noise_deg;
  j["seed"] = s.simulation.seed;
  j["loop_kernel"] = run.loop_kernel;
  return j;
}

nlohmann::ordered_json RunReportJson(const RunDescription& run, const SimulationResult& result,
                                     const std::vector<std::string>& warnings) {
  const RunSummary& r = result.summary;
  nlohmann::ordered_json j = RunSettingsJson(run);
  j["samples"] = r.samples;
  j["samples_per_s"] = Number(result.samples_per_s);
  j["wall_time_s"] = Number(result.wall_time_s);
  j["stopped_early"] = result.stopped_early;
  j["error_deg"] = {{"mean", Number(r.error_deg.mean)},
                    {"p50", Number(r.error_deg.p50)},
                    {"p99", Number(r.error_deg.p99)},
                    {"max", Number(r.error_deg.max)}};
  j["extinction_db_mean"] = Number(r.extinction_db_mean);
  j["extinction_db_power_mean"] = Number(r.extinction_db_power_mean);
  j["lock_threshold_deg"] = run.scenario.simulation.lock_threshold_deg;
  j["lock_time_s"] = Optional(r.lock_time_s);
  j["first_lock_time_s"] = Optional(r.first_lock_time_s);
  j["excursions"] = r.excursions;
  j["threshold_crossings"] = r.threshold_crossings;
  j["recovery"] = {{"threshold_deg", Number(RunStatistics::kRecoveryThresholdDeg)},
                   {"stretches_above", r.recovery_stretches},
                   {"longest_above_s", Number(r.longest_recovery_s)},
                   {"longest_above_from_s", Number(r.longest_recovery_from_s)}};
  j["statistics_from_s"] = Number(r.statistics_start_s);
  j["statistics_to_s"] = Number(r.statistics_end_s);
  j["statistics_samples"] = r.statistics_samples;
  j["phi_min"] = Array(r.phi_min);
  j["phi_max"] = Array(r.phi_max);
  j["phi_p1"] = Array(r.phi_p1);
  j["phi_p99"] = Array(r.phi_p99);
  j["nullspace_active_fraction"] = Number(r.nullspace_active_fraction);
  j["resets"] = r.resets;
  j["updates"] = r.updates;
  j["failed_updates"] = r.failed_updates;
  j["rank_deficient_updates"] = r.rank_deficient_updates;
  j["clamped_updates"] = r.clamped_updates;
  j["sigma_min_min"] = Number(r.sigma_min_min);
  j["near_singular_fraction"] = Number(r.near_singular_fraction);
  nlohmann::ordered_json final_phi = nlohmann::ordered_json::array();
  for (int i = 0; i < result.final_phi.size(); ++i) final_phi.push_back(Number(result.final_phi[i]));
  j["final_phi"] = final_phi;
  j["warnings"] = warnings;
  return j;
}

std::string RunReportText(const RunDescription& run, const SimulationResult& result) {
  const ScenarioConfig& s = run.scenario;
  const RunSummary& r = result.summary;
  std::string text;
  text += fmt::format("scenario   {} — {} ({} controls), {} loop, method {}, step {:g}",
                      s.name, run.device, run.controls,
                      s.controller.loop == LoopMode::kModel ? "model" : "measured",
                      MethodName(s.controller.method), s.controller.step);
  if (s.controller.method == ControlMethod::kGradientProjection ||
      s.controller.method == ControlMethod::kThresholdedGradientProjection ||
      s.controller.method == ControlMethod::kExtendedJacobian) {
    text += fmt::format(", null-space step {:g}", s.controller.nullspace_step);
  }
  if (const std::string options = OptionsText(s.controller); !options.empty()) {
    text += "\noptions    " + options;
  }
  text += fmt::format("\ninput      {:.4g} rad/s, target {}\n", InputRateRadPerS(s), run.target);
  text += fmt::format("run        {} samples at {:.4g} MHz, delay {} samples, control from {:.4g} ms"
                      "{}\n",
                      r.samples, s.simulation.sample_rate_hz / 1e6, run.delay_samples,
                      s.controller.activation_s * 1e3, result.stopped_early ? " (stopped early)" : "");
  text += fmt::format("speed      {:.3g} M samples/s ({:.3g} s, {} loop)\n",
                      result.samples_per_s / 1e6, result.wall_time_s, run.loop_kernel);
  // The first lock first; excursions counted with hysteresis (the raw crossings beside them);
  // the last relock only when it is not the first lock.
  const double threshold_deg = s.simulation.lock_threshold_deg;
  if (!r.first_lock_time_s) {
    text += fmt::format("lock       never below {:g}°\n", threshold_deg);
  } else {
  text += fmt::format("lock       first below {:g}° after {}; {} excursion{} above it (a new one after the error "
                      "fell below {:g}°; {} crossings)",
                      threshold_deg, FormatOptional(r.first_lock_time_s, 1e3, "ms"), r.excursions,
                      r.excursions == 1 ? "" : "s", threshold_deg / 2, r.threshold_crossings);
  if (!r.lock_time_s) {
    text += "; above it at the end\n";
  } else if (*r.lock_time_s > *r.first_lock_time_s) {
    text += fmt::format("; below since {}\n", FormatOptional(r.lock_time_s, 1e3, "ms"));
  } else {
    text += "; below ever since\n";
  }
  }
  text += fmt::format("error      mean {:.3f}°  p50 {:.3f}°  p99 {:.3f}°  max {:.3f}°  "
                      "(window {:.4g}–{:.4g} ms, {} samples)\n",
                      r.error_deg.mean, r.error_deg.p50, r.error_deg.p99, r.error_deg.max,
                      r.statistics_start_s * 1e3, r.statistics_end_s * 1e3, r.statistics_samples);
  text += fmt::format("extinction mean {:.2f} dB, power-averaged {:.2f} dB\n", r.extinction_db_mean,
                      r.extinction_db_power_mean);
  if (r.recovery_stretches == 0) {
    text += fmt::format("recovery   never at or above {:.3f}° (40 dB) in the window\n",
                        RunStatistics::kRecoveryThresholdDeg);
  } else {
    text += fmt::format("recovery   {} stretch{} at or above {:.3f}° (40 dB); the longest {:.3g} µs from {:.6g} ms\n",
                        r.recovery_stretches, r.recovery_stretches == 1 ? "" : "es",
                        RunStatistics::kRecoveryThresholdDeg, r.longest_recovery_s * 1e6,
                        r.longest_recovery_from_s * 1e3);
  }
  text += fmt::format("phi        min [{}]\n           max [{}]\n           p1  [{}]\n"
                      "           p99 [{}]\n",
                      FormatList(r.phi_min), FormatList(r.phi_max), FormatList(r.phi_p1),
                      FormatList(r.phi_p99));
  text += fmt::format("controller null-space active {:.1f}% of updates, {} failed, {} rank-deficient, "
                      "{} clamped, {} resets, smallest sigma_min {:.3g} ({:.2f}% of updates "
                      "below 0.1 sigma_max)\n",
                      100.0 * r.nullspace_active_fraction, r.failed_updates,
                      r.rank_deficient_updates, r.clamped_updates, r.resets, r.sigma_min_min,
                      100.0 * r.near_singular_fraction);
  return text;
}

std::string DescribeSweepSpeed(const std::vector<SweepOutcome>& outcomes, int threads, double wall_s) {
  int64_t samples = 0;
  for (const SweepOutcome& outcome : outcomes) {
    if (outcome.ok) samples += outcome.result.summary.samples;
  }
  const int used = SweepThreads(threads, std::max<size_t>(1, outcomes.size()));
  const BatchIsa isa = ChosenBatchIsa();
  return fmt::format("{} run{}, {:.2g} samples in {:.2f} s: {:.1f} M samples/s on {} thread{}, {}",
                     outcomes.size(), outcomes.size() == 1 ? "" : "s", static_cast<double>(samples),
                     wall_s, wall_s > 0.0 ? static_cast<double>(samples) / wall_s / 1e6 : 0.0, used,
                     used == 1 ? "" : "s",
                     isa == BatchIsa::kNone
                         ? std::string("one run at a time per thread (no SIMD batches)")
                         : fmt::format("runs of one kind in {} batches of up to {}", BatchIsaName(isa),
                                       BatchLanesOf(isa)));
}

}  // namespace dpc::cli
