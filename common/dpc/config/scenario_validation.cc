// The scenario as a whole: the simulation, input and target checks, the sample counts
// (DelaySamples, TotalSamples) and ValidateScenario, which runs every part in order and the
// rules that span parts. The device and controller parts are device_validation.cc and
// controller_validation.cc; the field checks they all share are field_checks.h.

#include "dpc/config/scenario_validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "dpc/config/field_checks.h"

namespace dpc {
namespace {

using field_checks::Fail;
using field_checks::FormatVector;
using field_checks::kSampleCountTolerance;
using field_checks::RequireAxis;
using field_checks::RequireFinite;
using field_checks::RequireFiniteVector;
using field_checks::RequireNonNegative;
using field_checks::RequirePositive;
using field_checks::RequireRate;
using field_checks::RequireUnitStokes;

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

void ValidateRecordedInput(const RecordedInput& recorded, const InputConfig& input) {
  if (recorded.sops.empty()) Fail("input.recorded", fmt::format("{}: no sample", recorded.source));
  if (recorded.sops.size() > static_cast<size_t>(kMaxRecordedInputSamples)) {
    Fail("input.recorded", fmt::format("{}: {} samples; at most {}", recorded.source, recorded.sops.size(),
                                       kMaxRecordedInputSamples));
  }
  if (!input.disturbances.empty()) {
    Fail("input.disturbances", fmt::format("{} disturbances beside a recorded input ({}); a recorded input is the "
                                           "whole input",
                                           input.disturbances.size(), recorded.source));
  }
  for (size_t k = 0; k < recorded.sops.size(); ++k) {
    RequireUnitStokes(recorded.sops[k], fmt::format("input.recorded[{}]", k));
  }
}

void ValidateInput(const InputConfig& input, double sample_rate_hz) {
  if (input.recorded != nullptr) {
    ValidateRecordedInput(*input.recorded, input);
    return;
  }
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

int64_t DelaySamples(const SimulationConfig& simulation) {
  return SaturatingRound(simulation.delay_s * simulation.sample_rate_hz);
}

int64_t TotalSamples(const SimulationConfig& simulation) {
  return SaturatingRound(simulation.duration_s * simulation.sample_rate_hz);
}

void ValidateTargetConfig(const TargetConfig& target) { ValidateTarget(target); }

void ValidateControllerForStages(const ControllerConfig& controller,
                                 const std::vector<StageConfig>& stages) {
  // The range criterion needs a range to keep the controls in.
  if (controller.nullspace_criterion == NullspaceCriterion::kRange) {
    bool any_range = false;
    for (const StageConfig& stage : stages) {
      any_range = any_range || stage.range || (stage.retardance.controlled && stage.retardance.range) ||
                  (stage.orientation.controlled && stage.orientation.range);
    }
    if (!any_range) {
      Fail("controller.nullspace_criterion",
           "RANGE keeps the controls inside their ranges, but no stage has a range; give "
           "stages[i].range (e.g. { min: -1 max: 1 })");
    }
  }
  // gpt runs the null-space term only while some |φ_i| exceeds its threshold. Every
  // command is kept inside the ranges (the range criterion, or the integrator's clamp), so when
  // every control has a range whose ends all lie within the threshold, the term never runs and
  // the controls pile up at their ends.
  if (controller.method == ControlMethod::kThresholdedGradientProjection) {
    std::vector<std::pair<std::string, const std::optional<ControlRange>*>> ranges;
    CollectRanges(stages, &ranges);
    bool every_control_ranged = true;
    double reach = 0.0;  // the largest |φ_i| any range lets a control take
    for (const auto& [path, range] : ranges) {
      if (!*range) {
        every_control_ranged = false;
        break;
      }
      reach = std::max({reach, std::abs((*range)->min), std::abs((*range)->max)});
    }
    if (every_control_ranged && !(controller.threshold < reach)) {
      Fail("controller.threshold",
           fmt::format("gpt runs the null-space term only while some |phi_i| > {}, but every "
                       "control is kept within its range, and no range reaches beyond |phi| = {}: "
                       "the term would never run; give a threshold below {} (or use gp)",
                       controller.threshold, reach, reach));
    }
  }
}

void ValidateScenario(const ScenarioConfig& scenario) {
  ValidateSimulation(scenario.simulation);
  ValidateDeviceStages(scenario.stages);
  ValidateInput(scenario.input, scenario.simulation.sample_rate_hz);
  ValidateTarget(scenario.target);
  ValidateControllerConfig(scenario.controller, ScenarioControlCount(scenario.stages),
                           scenario.target, scenario.simulation);
  if (scenario.waveplate_device) ValidateWaveplateDevice(*scenario.waveplate_device, scenario.stages);
  if (scenario.polarimeter_device) ValidatePolarimeterDevice(*scenario.polarimeter_device);
  ValidateControllerForStages(scenario.controller, scenario.stages);
}

}  // namespace dpc
