#pragma once
// A closed-loop scenario as plain structs with defaults: the device (stages), the input SOP
// and its disturbances, the target, the controller and the simulation settings.
//
// The structure and the field names mirror the Protobuf schema common/proto/dpc/scenario.proto
// one to one, so that ValidateScenario (scenario_validation.h) can name a bad field by the path
// a user wrote in the text file, e.g. "stages[1].map.table.angle_rad[3]". The core never
// depends on Protobuf: the scenario_io library converts text format into these structs.
//
// The defaults are the paper's scenario (section IV): R1R3R1, θ = π·φ, target [0, 0.6, 0.8],
// input rotating about S3 at 100 krad/s with random kicks about S2, 50 MHz sampling, 1 µs loop
// delay, control from 2 ms, gradient projection with step 0.1.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dpc/control/controller_config.h"
#include "dpc/optics/stokes.h"
#include "dpc/optics/waveplate_stage.h"

namespace dpc {

/// scenario.proto TableAtCondition: a lookup table measured at one temperature or wavelength.
struct ConditionTableConfig {
  double condition = 0.0;                  ///< °C or nm (ControlMapConfig::condition)
  std::vector<double> control;             ///< φ points, strictly increasing
  std::vector<double> angle_rad;           ///< θ points, strictly monotonic
};

/// scenario.proto ControlMap.
struct ControlMapConfig {
  enum class Kind { kLinear, kPolynomial, kTable, kTablesByCondition };
  /// What a kTablesByCondition map's tables are keyed by.
  enum class Condition { kTemperatureC, kWavelengthNm };
  /// The most tables a kTablesByCondition map may have.
  static constexpr int kMaxConditionTables = 16;

  Kind kind = Kind::kLinear;
  double rad_per_unit = M_PI;              ///< linear: θ = rad_per_unit·φ + offset_rad
  double offset_rad = 0.0;
  std::vector<double> coefficients_rad;    ///< polynomial: θ = Σ c_j φ^j, c_0 first
  std::vector<double> table_control;       ///< table: φ points, strictly increasing
  std::vector<double> table_angle_rad;     ///< table: θ points, strictly monotonic
  // tables_by_condition: the tables and the operating point, interpolated between the two
  // tables around it (ResolveConditionTables, scenario_builders.h).
  Condition condition = Condition::kTemperatureC;
  double operating_point = 0.0;            ///< °C or nm
  std::vector<ConditionTableConfig> condition_tables;  ///< conditions strictly increasing
};

/// scenario.proto StageAngle: an adjustable-axis stage's retardance θ or orientation ϕ.
struct StageAngleConfig {
  bool controlled = false;       ///< false: fixed at fixed_rad
  double fixed_rad = 0.0;
  ControlMapConfig map;          ///< when controlled
  std::optional<ControlRange> range;
};

/// scenario.proto Stage.
struct StageConfig {
  enum class Kind { kFixedAxis, kAdjustableAxis };
  Kind kind = Kind::kFixedAxis;
  std::string name;
  // Fixed-axis stage.
  Vector3 axis = Vector3::UnitX();   ///< unit after validation (any non-zero length accepted)
  ControlMapConfig map;
  std::optional<ControlRange> range;
  // Adjustable-axis stage R3(ϕ) R1(θ) R3ᵀ(ϕ).
  StageAngleConfig retardance;
  StageAngleConfig orientation;
};

/// scenario.proto Target.
struct TargetConfig {
  enum class Kind { kPoint, kSet };
  Kind kind = Kind::kPoint;
  StokesVector point = StokesVector(0.0, 0.6, 0.8);
  Vector3 normal = Vector3::UnitZ();  ///< set: normal·S = offset
  double offset = 0.0;
};

/// scenario.proto Disturbance. Which fields apply depends on the kind.
struct DisturbanceConfig {
  enum class Kind { kPaperScrambler, kRandomWalk, kConstantRotation, kTransientBurst };
  enum class Envelope { kRectangular, kHalfSine };
  Kind kind = Kind::kPaperScrambler;

  /// paper_scrambler: the constant rotation rate about `axis`; constant_rotation: its rate;
  /// transient_burst: the peak rate.
  double rate_rad_per_s = 1e5;
  /// paper_scrambler: rotation axis (default S3); constant_rotation / transient_burst: the axis.
  Vector3 axis = Vector3::UnitZ();
  /// paper_scrambler: the random kick per sample about kick_axis is N(0, σ²) with
  /// σ = kick_rms_ratio · rate_rad_per_s / sample_rate_hz.
  double kick_rms_ratio = 1.0;
  Vector3 kick_axis = Vector3::UnitY();
  /// random_walk: isotropic rotation diffusion; per sample a rotation vector N(0, D²·dt·I₃).
  double diffusion_rad_per_sqrt_s = 0.0;
  /// transient_burst: first burst start, burst length, repetition period (0: once), envelope
  /// of the rate (peak rate_rad_per_s), and whether each burst picks a random axis.
  double start_s = 0.0;
  double duration_s = 0.0;
  double period_s = 0.0;
  Envelope envelope = Envelope::kHalfSine;
  bool random_axis = false;
};

/// An input SOP taken from a recording (a bench session's measured S_in, one per sample),
/// instead of a simulated one. Never written in a scenario file: a program that reads the
/// recording sets it (dpc-polarimeter --input-recording, dpc evaluate).
struct RecordedInput {
  std::string source;                ///< where it comes from (a file name), for descriptions
  std::vector<StokesVector> sops;    ///< S_in[k] for sample k, unit vectors
};

/// scenario.proto Input.
struct InputConfig {
  StokesVector initial_sop = StokesVector::UnitX();
  /// Applied in order on every sample. Empty: the input SOP holds still.
  std::vector<DisturbanceConfig> disturbances;
  /// Set: S_in[k] = recorded->sops[k] (the last one held past its end); initial_sop is then
  /// sops[0] and there are no disturbances (validation refuses them beside it). Shared, not
  /// copied, with every copy of the scenario (a recording holds millions of samples).
  std::shared_ptr<const RecordedInput> recorded;
};

/// scenario.proto Simulation.
struct SimulationConfig {
  double sample_rate_hz = 50e6;
  /// Loop delay: a command computed from the sample at time t acts from t + delay_s. A whole
  /// number (≥ 1) of sample periods.
  double delay_s = 1e-6;
  double duration_s = 10e-3;
  /// Polarimeter noise: each measured SOP is perturbed by a rotation with independent N(0, σ²)
  /// components per tangent axis, σ in degrees (0: ideal polarimeters).
  double polarimeter_noise_deg = 0.0;
  uint64_t seed = 1;
  /// Lock: the error stays below this (degrees) from the lock time to the end.
  double lock_threshold_deg = 10.0;
  /// Error statistics start here (seconds); unset: settle_samples after the first lock after
  /// activation (the run's first sample below lock_threshold_deg), so that the lock-in transient
  /// does not count as tracking error. A run that never locks has no error statistics.
  std::optional<double> statistics_start_s;
  int64_t settle_samples = 1000;
};

/// scenario.proto InstrumentLink: how a line-protocol instrument (SCPI-like text lines ending
/// in "\n") is reached, over TCP or a serial port.
struct InstrumentLinkConfig {
  enum class Kind { kTcp, kSerial };
  Kind kind = Kind::kTcp;
  std::string host = "127.0.0.1";   ///< tcp: an IPv4 address (no name lookup)
  int port = 0;                     ///< tcp: 1…65535
  std::string path;                 ///< serial: the device (/dev/ttyUSB0, a pseudo-terminal)
  int baud = 115200;                ///< serial
  /// A reply later than this is a fault (the device is then held, reconnected, re-applied).
  double response_timeout_s = 0.05;
  /// Reconnection after a fault: first after reconnect_min_s, then doubling up to reconnect_max_s.
  double reconnect_min_s = 0.05;
  double reconnect_max_s = 2.0;
};

/// scenario.proto WaveplateDevice: an electronic polarization controller driven over a line
/// protocol. Each control φ_i IS the voltage of one channel (the stage maps give retardance
/// against volts), quantized to the device's DAC.
struct WaveplateDeviceConfig {
  InstrumentLinkConfig link;
  /// The line that sets one channel: fmt syntax with {channel}, {volts} (e.g. {volts:.4f}) and
  /// {code} (the DAC code).
  std::string set_command = ":SOUR{channel}:VOLT {volts:.4f}";
  std::vector<int> channels;        ///< per control; empty: 1, 2, …
  std::string ack = "OK";           ///< the reply to every set; empty: no reply expected
  /// The query that reads one channel's voltage back ({channel}): a driver that starts (or
  /// reconnects after the device lost power) takes the waveplates where they are; empty: none.
  std::string read_command = ":SOUR{channel}:VOLT?";
  std::string identify = "*IDN?";   ///< sent on connecting, its reply logged; empty: none
  double volts_min = -10.0;         ///< the DAC's full scale
  double volts_max = 10.0;
  int dac_bits = 16;                ///< 0: no quantization
  double max_slew_v_per_s = 1e4;    ///< the device's own slew limit
  /// After a set the device's output takes this long to settle: it is not set again before
  /// (newer commands are coalesced meanwhile), and dpc calibrate waits at least this long.
  double settling_s = 0.0;
};

/// scenario.proto PolarimeterDevice: a polarimeter queried over a line protocol once per
/// sample; its reply holds S_out, S_in or both as comma-separated normalized Stokes values.
struct PolarimeterDeviceConfig {
  enum class Reply { kOutput, kInput, kInputAndOutput };
  InstrumentLinkConfig link;
  std::string query = ":MEAS:SOP?";
  Reply reply = Reply::kOutput;
  /// A reply whose |S| (the degree of polarization) is below this is refused: no direction.
  double min_dop = 0.1;
  /// The reply ends with one more field: the optical power in watts (published with the sample).
  bool reports_power = false;
  /// Stream mode: the instrument sends readings by itself, one line each, at its own rate; the
  /// query is not sent. Each line is a sample when it arrives (the newest one when several
  /// are waiting: the others are counted as skipped).
  bool stream = false;
  /// Sent at every connection in stream mode to start the stream ("": the instrument streams
  /// by itself). No reply is expected.
  std::string stream_start;
};

/// scenario.proto Scenario.
struct ScenarioConfig {
  std::string name = "paper";
  std::string description;
  std::vector<StageConfig> stages;   ///< empty after defaults means nothing: validation rejects
  InputConfig input;
  TargetConfig target;
  ControllerConfig controller;
  SimulationConfig simulation;
  /// Real instruments (unset: the simulated device and bench).
  std::optional<WaveplateDeviceConfig> waveplate_device;
  std::optional<PolarimeterDeviceConfig> polarimeter_device;
};

/// The paper's section IV scenario with `axes` (e.g. "131", "3131"; see
/// WaveplateChain::FromAxes): linear θ = π·φ stages, the paper scrambler at 100 krad/s.
ScenarioConfig PaperScenario(const std::string& axes = "131");

/// Fixed-axis stages with θ = π·φ along the elemental axes of `axes` ("131" → S1, S3, S1).
/// Throws std::invalid_argument for characters other than 1, 2, 3.
std::vector<StageConfig> StagesFromAxes(const std::string& axes);

}  // namespace dpc
