#pragma once
// The one place that checks a scenario (scenario_config.h) before anything is built from it.
//
// ValidateScenario throws a ScenarioError at the first problem, located by the field's path in
// scenario.proto ("stages[2].axis_vector", "input.disturbances[0].paper_scrambler.
// rate_rad_per_s", "controller.initial_phi[1]"). A non-finite double anywhere is reported at
// its own path (a Vector3 component as ".s1", ".s2", ".s3"). Only the fields that apply to an
// entry's kind are checked (a linear map's table is ignored, as in the text format).
//
// The sections are checked in the order simulation, stages, input, target, controller: the
// later checks use the sample rate, the duration and the control count.
//
// Where each part lives (this is the one header for all of them): stages and maps in
// device_validation.cc; controller, dither and options in controller_validation.cc;
// simulation, input, target, the sample counts and ValidateScenario (with the RANGE rule, which
// needs the stages) in scenario_validation.cc; the field checks and their wording, shared by
// all, in field_checks.h.
//
// Rules, with fs = simulation.sample_rate_hz and dt = 1/fs:
//   simulation   0 < fs ≤ 1e10 Hz; delay_s = k·dt with k a whole number (relative tolerance
//                1e-6), 1 ≤ k ≤ 1e7 (a command cannot act on the sample it was computed from);
//                duration_s > 0 and 1 ≤ round(duration_s·fs) ≤ 1e12 samples;
//                polarimeter_noise_deg ∈ [0, 180]; lock_threshold_deg ∈ (0, 180];
//                statistics_start_s (if set) ∈ [0, duration_s).
//   stages       1 … kMaxStages entries, at most kMaxControls controls in all.
//                Fixed-axis: |axis| ≥ 1e-9; map; range (if set) min < max.
//                Adjustable-axis: retardance and/or orientation controlled; each either a
//                finite fixed_rad, or a map and a range.
//   map          linear: rad_per_unit ≠ 0. polynomial: 2 … 16 coefficients, not constant.
//                table: 2 … 4096 (control, angle_rad) pairs, control strictly increasing,
//                angle_rad strictly monotonic.
//   input        initial_sop a unit Stokes vector (| |S| − 1 | ≤ 1e-6); at most
//                kMaxDisturbances disturbances. Rates ≥ 0 (the axis sets the direction) and
//                rate·dt < π rad per sample (the simulation could not resolve faster turns);
//                axes non-zero. transient_burst: start_s ≥ 0, duration_s > 0, period_s = 0 or
//                ≥ duration_s. A recorded input (set by a program, never by a file): 1 …
//                kMaxRecordedInputSamples unit Stokes vectors and no disturbances beside it.
//   target       point: a unit Stokes vector. set n·S = c: |n| ≥ 1e-9, |c|/|n| < 1.
//   controller   0 < step ≤ 1e6, and < 2 for every law but transpose and dither (the error
//                contracts by (1 − step) per update); 0 ≤ nullspace_step < 2; threshold,
//                damping ∈ [0, 1e6] (damping > 0 for rls);
//                singular_value_tolerance ∈ (0, 1); activation_s ∈ [0, duration_s);
//                initial_phi empty or one value per control; inverse and damped need a square
//                task (3 controls for a point target, 1 for a set); dither: amplitude > 0,
//                0 ≤ settle_samples ≤ 1e7, reset_threshold > 0, dt ≤ reset_duration_s ≤ 1e7·dt;
//                singularity_damping (GP, GPT only): 0 < max_damping, threshold ≤ 1e3;
//                nullspace_criterion RANGE and curvature_correction: GP or GPT (RANGE also
//                needs some stage with a range);
//                prediction: loop MODEL, not DITHER, 0 < window_samples ≤ 1e9,
//                0 ≤ horizon_samples, lead_samples ≤ 1e9.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"

namespace dpc {

/// The most disturbances an input may have.
inline constexpr int kMaxDisturbances = 16;
/// A recorded input holds at most this many samples (24 bytes each: 2.4 GB).
inline constexpr int64_t kMaxRecordedInputSamples = 100'000'000;
/// The longest loop delay (and dither settle / reset time), in samples.
inline constexpr int64_t kMaxDelaySamples = 10'000'000;
/// The most samples a run may have.
inline constexpr int64_t kMaxTotalSamples = 1'000'000'000'000;
/// The highest sample rate accepted, Hz.
inline constexpr double kMaxSampleRateHz = 1e10;
/// The largest task step, gpt threshold and damping accepted for any law (the transpose and
/// dithering laws' steps scale with the device; the others must be < 2).
inline constexpr double kMaxStep = 1e6;
/// The largest singularity damping λ0 and threshold ε accepted.
inline constexpr double kMaxSingularityDamping = 1e3;
/// The longest prediction window, horizon and lead accepted, in samples.
inline constexpr double kMaxPredictionSamples = 1e9;
/// The shortest axis or set normal accepted (they are normalized).
inline constexpr double kMinAxisLength = 1e-9;

/// Throws ScenarioError (location: the field path) at the first problem; returns if the
/// scenario can be built and run.
void ValidateScenario(const ScenarioConfig& scenario);

/// The parts of ValidateScenario that the bench services check on their own (a device
/// description or a target that arrives over DDS; a controller that joins an existing bench).
/// Same rules and field paths as in a scenario file.
void ValidateDeviceStages(const std::vector<StageConfig>& stages);
void ValidateTargetConfig(const TargetConfig& target);
void ValidateControllerConfig(const ControllerConfig& controller, int control_count,
                              const TargetConfig& target, const SimulationConfig& simulation);

/// The number of control signals the stages have: one per fixed-axis stage, one per controlled
/// angle of an adjustable-axis stage.
int ScenarioControlCount(const std::vector<StageConfig>& stages);
/// Each control's range (set or not), in control order, with its field path.
void CollectRanges(const std::vector<StageConfig>& stages,
                   std::vector<std::pair<std::string, const std::optional<ControlRange>*>>* out);
/// The rules between the controller and the device's stages (a scenario's, or the driver's
/// device description): the range criterion needs a range; gpt's threshold must lie within
/// reach of some control (not every control ranged within it).
void ValidateControllerForStages(const ControllerConfig& controller,
                                 const std::vector<StageConfig>& stages);

/// An instrument's command or reply line holds at most this many bytes.
inline constexpr size_t kMaxInstrumentLineBytes = 200;

/// The real instruments (instrument_validation.cc). A waveplate device: a reachable link (an
/// IPv4 address and port, or an absolute serial path and a standard baud rate), timeouts and
/// reconnection delays in range, a set command that formats with {channel}, {volts}, {code}
/// into one line, one distinct channel per control, a DAC full scale, and a range inside that
/// full scale for every control. A polarimeter device: a link, a query, min_dop in (0, 1].
void ValidateWaveplateDevice(const WaveplateDeviceConfig& device, const std::vector<StageConfig>& stages);
void ValidatePolarimeterDevice(const PolarimeterDeviceConfig& device);

/// The line that sets `channel` to `volts` (DAC `code`) from a set_command template. Throws
/// fmt::format_error for a template ValidateWaveplateDevice refuses.
std::string FormatSetCommand(const std::string& set_command, int channel, double volts, int64_t code);

/// The loop delay in samples, round(delay_s·sample_rate_hz). For a validated config; otherwise
/// saturated to [0, INT64_MAX] (0 for NaN).
int64_t DelaySamples(const SimulationConfig& simulation);

/// The run length in samples, round(duration_s·sample_rate_hz). For a validated config;
/// otherwise saturated like DelaySamples.
int64_t TotalSamples(const SimulationConfig& simulation);

}  // namespace dpc
