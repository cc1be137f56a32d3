#pragma once
// Scenario texts for the scenario_io tests (every field and branch), and field-by-field
// comparison of scenarios (exact: text format round-trips doubles).

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/scenario_io/scenario_reader.h"

namespace dpc::testing {

// ---------------------------------------------------------------------------------------------
// Two valid scenarios that together set every double field of scenario.proto (each to a
// non-zero value, so that proto3 records it as present) and every oneof branch that holds one.

/// Fixed-axis stages of every map kind, every disturbance, a point target, every controller
/// and simulation field.
constexpr const char* kFixedAxisText = R"pb(
name: "every-fixed-axis-field"
description: "fixed-axis stages, every disturbance, a point target"
stages {
  name: "vector"
  axis_vector { s1: 0.1 s2: 0.2 s3: 0.9 }
  map { linear { rad_per_unit: 3.1 offset_rad: 0.2 } }
  range { min: -2 max: 2 }
}
stages {
  axis: S3
  map { polynomial { coefficients_rad: [ 0.1, 3.0, 0.2 ] } }
}
stages {
  axis: S1
  map { table { control: [ -1, 0.25, 1 ] angle_rad: [ -3, 0.5, 3 ] } }
}
input {
  initial_sop { s1: 0.48 s2: 0.6 s3: 0.64 }
  disturbances {
    paper_scrambler {
      rate_rad_per_s: 2e5
      kick_rms_ratio: 0.5
      rotation_axis_vector { s1: 0.1 s2: 0.2 s3: 1 }
      kick_axis_vector { s1: 0.3 s2: 1 s3: 0.1 }
    }
  }
  disturbances { random_walk { diffusion_rad_per_sqrt_s: 10 } }
  disturbances {
    constant_rotation { rate_rad_per_s: 1e4 axis_vector { s1: 1 s2: 0.5 s3: 0.25 } }
  }
  disturbances {
    transient_burst {
      start_s: 1e-3
      duration_s: 1e-4
      rate_rad_per_s: 5e6
      period_s: 2e-3
      envelope: RECTANGULAR
      axis_vector { s1: 0.5 s2: 0.5 s3: 0.5 }
    }
  }
}
target { point { s1: 0.48 s2: 0.6 s3: 0.64 } }
controller {
  method: PINV
  step: 0.2
  nullspace_step: 0.05
  threshold: 0.9
  damping: 2e-3
  singular_value_tolerance: 1e-10
  loop: MEASURED
  activation_s: 1e-3
  initial_phi: [ 0.1, 0.2, 0.3 ]
  dither { amplitude: 0.01 settle_samples: 3 reset_threshold: 0.8 reset_duration_s: 2e-6 }
}
simulation {
  sample_rate_hz: 40e6
  delay_s: 0.5e-6
  duration_s: 4e-3
  polarimeter_noise_deg: 0.5
  seed: 3
  lock_threshold_deg: 5
  statistics_start_s: 3e-3
}
)pb";

/// Adjustable-axis stages with fixed and controlled angles of every map kind, a set target.
constexpr const char* kAdjustableAxisText = R"pb(
name: "every-adjustable-axis-field"
stages {
  name: "qwp"
  adjustable_axis {
    retardance { fixed_rad: 1.57 }
    orientation {
      controlled {
        map { linear { rad_per_unit: 2 offset_rad: 0.1 } }
        range { min: -1 max: 1 }
      }
    }
  }
}
stages {
  adjustable_axis {
    retardance {
      controlled {
        map { table { control: [ 0.5, 1, 2 ] angle_rad: [ 3, 2, 0.5 ] } }
        range { min: 0.5 max: 1.5 }
      }
    }
    orientation { fixed_rad: 0.3 }
  }
}
stages {
  adjustable_axis {
    retardance { controlled { map { polynomial { coefficients_rad: [ 0.5, 1.5 ] } } } }
    orientation { controlled {} }
  }
}
input { disturbances { transient_burst { duration_s: 2e-5 random_axis: true } } }
target { set { normal { s1: 0.1 s2: 0.2 s3: 1 } offset: 0.3 } }
controller {
  method: GPT
  initial_phi: [ 0.1, 0.2, 0.3, 0.4 ]
  singularity_damping { max_damping: 0.4 threshold: 0.3 }
  nullspace_criterion: RANGE
  prediction { window_samples: 500 horizon_samples: 20 lead_samples: 4 }
}
)pb";

inline ScenarioConfig FromText(const std::string& text) {
  return ScenarioFromProto(ParseScenarioText(text, "test.pbtxt"));
}

/// The error parsing and converting `text` raises, or nullopt.
inline std::optional<ScenarioError> ErrorOf(const std::string& text) {
  try {
    FromText(text);
  } catch (const ScenarioError& e) {
    return e;
  }
  return std::nullopt;
}

// ---- Field-by-field comparison (exact: text format round-trips doubles).

inline void ExpectSameRange(const std::optional<ControlRange>& a, const std::optional<ControlRange>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_EQ(a->min, b->min);
  EXPECT_EQ(a->max, b->max);
}

inline void ExpectSameMap(const ControlMapConfig& a, const ControlMapConfig& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.rad_per_unit, b.rad_per_unit);
  EXPECT_EQ(a.offset_rad, b.offset_rad);
  EXPECT_EQ(a.coefficients_rad, b.coefficients_rad);
  EXPECT_EQ(a.table_control, b.table_control);
  EXPECT_EQ(a.table_angle_rad, b.table_angle_rad);
  EXPECT_EQ(a.condition, b.condition);
  EXPECT_EQ(a.operating_point, b.operating_point);
  ASSERT_EQ(a.condition_tables.size(), b.condition_tables.size());
  for (size_t i = 0; i < a.condition_tables.size(); ++i) {
    EXPECT_EQ(a.condition_tables[i].condition, b.condition_tables[i].condition);
    EXPECT_EQ(a.condition_tables[i].control, b.condition_tables[i].control);
    EXPECT_EQ(a.condition_tables[i].angle_rad, b.condition_tables[i].angle_rad);
  }
}

inline void ExpectSameAngle(const StageAngleConfig& a, const StageAngleConfig& b) {
  EXPECT_EQ(a.controlled, b.controlled);
  EXPECT_EQ(a.fixed_rad, b.fixed_rad);
  ExpectSameMap(a.map, b.map);
  ExpectSameRange(a.range, b.range);
}

/// Maps measured at several conditions: tables keyed by temperature (two grids), and by wavelength
/// on an adjustable-axis stage's orientation.
constexpr const char* kConditionTablesText = R"pb(
name: "tables-by-condition"
stages {
  axis: S1
  map {
    tables_by_condition {
      operating_temperature_c: 30
      tables { temperature_c: 15 table { control: [ -1, 0, 1 ] angle_rad: [ -3, 0, 3 ] } }
      tables { temperature_c: 35 table { control: [ -1, 0.5, 1 ] angle_rad: [ -3.2, 1.6, 3.2 ] } }
    }
  }
}
stages { axis: S3 }
stages {
  adjustable_axis {
    retardance { fixed_rad: 1.5707963267948966 }
    orientation {
      controlled {
        map {
          tables_by_condition {
            operating_wavelength_nm: 1550
            tables { wavelength_nm: 1500 table { control: [ 0, 1 ] angle_rad: [ 0, 2 ] } }
            tables { wavelength_nm: 1600 table { control: [ 0, 1 ] angle_rad: [ 0, 1.8 ] } }
          }
        }
      }
    }
  }
}
)pb";

/// Real instruments: a serial EPC with every field, a TCP polarimeter measuring both SOPs.
constexpr const char* kInstrumentsText = R"pb(
name: "instruments"
stages { name: "wp1" axis: S1 map { table { control: [ -10, 0, 10 ] angle_rad: [ -6.1, 0, 6.4 ] } } range { min: -9 max: 9 } }
stages { name: "wp2" axis: S3 map { linear { rad_per_unit: 0.6 } } range { min: -9 max: 9 } }
stages { name: "wp3" axis: S1 map { linear { rad_per_unit: 0.6 } } range { min: -9 max: 9 } }
waveplate_device {
  link { serial { path: "/dev/ttyUSB0" baud: 57600 } response_timeout_s: 0.02 reconnect_min_s: 0.1 reconnect_max_s: 5 }
  set_command: "CH{channel} DAC {code}"
  channels: [ 4, 2, 7 ]
  ack: "ACK"
  identify: "ID?"
  read_command: "CH{channel} V?"
  volts_min: -9.5
  volts_max: 9.5
  dac_bits: 14
  max_slew_v_per_s: 500
  settling_s: 0.002
}
polarimeter_device {
  link { tcp { host: "127.0.0.1" port: 5025 } response_timeout_s: 0.01 }
  query: "READ:BOTH?"
  reply: S_IN_AND_S_OUT
  min_dop: 0.3
  reports_power: true
  stream: true
  stream_start: "READ:STREAM ON"
}
)pb";

inline void ExpectSameLink(const InstrumentLinkConfig& a, const InstrumentLinkConfig& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.host, b.host);
  EXPECT_EQ(a.port, b.port);
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.baud, b.baud);
  EXPECT_EQ(a.response_timeout_s, b.response_timeout_s);
  EXPECT_EQ(a.reconnect_min_s, b.reconnect_min_s);
  EXPECT_EQ(a.reconnect_max_s, b.reconnect_max_s);
}

inline void ExpectSameInstruments(const ScenarioConfig& a, const ScenarioConfig& b) {
  ASSERT_EQ(a.waveplate_device.has_value(), b.waveplate_device.has_value());
  if (a.waveplate_device) {
    const WaveplateDeviceConfig &x = *a.waveplate_device, &y = *b.waveplate_device;
    ExpectSameLink(x.link, y.link);
    EXPECT_EQ(x.set_command, y.set_command);
    EXPECT_EQ(x.channels, y.channels);
    EXPECT_EQ(x.ack, y.ack);
    EXPECT_EQ(x.identify, y.identify);
    EXPECT_EQ(x.read_command, y.read_command);
    EXPECT_EQ(x.volts_min, y.volts_min);
    EXPECT_EQ(x.volts_max, y.volts_max);
    EXPECT_EQ(x.dac_bits, y.dac_bits);
    EXPECT_EQ(x.max_slew_v_per_s, y.max_slew_v_per_s);
    EXPECT_EQ(x.settling_s, y.settling_s);
  }
  ASSERT_EQ(a.polarimeter_device.has_value(), b.polarimeter_device.has_value());
  if (a.polarimeter_device) {
    const PolarimeterDeviceConfig &x = *a.polarimeter_device, &y = *b.polarimeter_device;
    ExpectSameLink(x.link, y.link);
    EXPECT_EQ(x.query, y.query);
    EXPECT_EQ(x.reply, y.reply);
    EXPECT_EQ(x.min_dop, y.min_dop);
    EXPECT_EQ(x.reports_power, y.reports_power);
    EXPECT_EQ(x.stream, y.stream);
    EXPECT_EQ(x.stream_start, y.stream_start);
  }
}

inline void ExpectSameScenario(const ScenarioConfig& a, const ScenarioConfig& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.description, b.description);
  ASSERT_EQ(a.stages.size(), b.stages.size());
  for (size_t i = 0; i < a.stages.size(); ++i) {
    SCOPED_TRACE(::testing::Message() << "stages[" << i << "]");
    const StageConfig &x = a.stages[i], &y = b.stages[i];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.axis, y.axis);
    ExpectSameMap(x.map, y.map);
    ExpectSameRange(x.range, y.range);
    ExpectSameAngle(x.retardance, y.retardance);
    ExpectSameAngle(x.orientation, y.orientation);
  }
  EXPECT_EQ(a.input.initial_sop, b.input.initial_sop);
  ASSERT_EQ(a.input.disturbances.size(), b.input.disturbances.size());
  for (size_t k = 0; k < a.input.disturbances.size(); ++k) {
    SCOPED_TRACE(::testing::Message() << "input.disturbances[" << k << "]");
    const DisturbanceConfig &x = a.input.disturbances[k], &y = b.input.disturbances[k];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.rate_rad_per_s, y.rate_rad_per_s);
    EXPECT_EQ(x.axis, y.axis);
    EXPECT_EQ(x.kick_rms_ratio, y.kick_rms_ratio);
    EXPECT_EQ(x.kick_axis, y.kick_axis);
    EXPECT_EQ(x.diffusion_rad_per_sqrt_s, y.diffusion_rad_per_sqrt_s);
    EXPECT_EQ(x.start_s, y.start_s);
    EXPECT_EQ(x.duration_s, y.duration_s);
    EXPECT_EQ(x.period_s, y.period_s);
    EXPECT_EQ(x.envelope, y.envelope);
    EXPECT_EQ(x.random_axis, y.random_axis);
  }
  EXPECT_EQ(a.target.kind, b.target.kind);
  EXPECT_EQ(a.target.point, b.target.point);
  EXPECT_EQ(a.target.normal, b.target.normal);
  EXPECT_EQ(a.target.offset, b.target.offset);
  const ControllerConfig &c = a.controller, &d = b.controller;
  EXPECT_EQ(c.method, d.method);
  EXPECT_EQ(c.step, d.step);
  EXPECT_EQ(c.nullspace_step, d.nullspace_step);
  EXPECT_EQ(c.threshold, d.threshold);
  EXPECT_EQ(c.damping, d.damping);
  EXPECT_EQ(c.singular_value_tolerance, d.singular_value_tolerance);
  EXPECT_EQ(c.loop, d.loop);
  EXPECT_EQ(c.activation_s, d.activation_s);
  EXPECT_EQ(c.initial_phi, d.initial_phi);
  EXPECT_EQ(c.dither.amplitude, d.dither.amplitude);
  EXPECT_EQ(c.dither.settle_samples, d.dither.settle_samples);
  EXPECT_EQ(c.dither.reset_threshold, d.dither.reset_threshold);
  EXPECT_EQ(c.dither.reset_duration_s, d.dither.reset_duration_s);
  const SimulationConfig &s = a.simulation, &t = b.simulation;
  EXPECT_EQ(s.sample_rate_hz, t.sample_rate_hz);
  EXPECT_EQ(s.delay_s, t.delay_s);
  EXPECT_EQ(s.duration_s, t.duration_s);
  EXPECT_EQ(s.polarimeter_noise_deg, t.polarimeter_noise_deg);
  EXPECT_EQ(s.seed, t.seed);
  EXPECT_EQ(s.lock_threshold_deg, t.lock_threshold_deg);
  EXPECT_EQ(s.statistics_start_s, t.statistics_start_s);
  EXPECT_EQ(s.settle_samples, t.settle_samples);
  ExpectSameInstruments(a, b);
}

// ---------------------------------------------------------------------------------------------
// Defaults.


}  // namespace dpc::testing
