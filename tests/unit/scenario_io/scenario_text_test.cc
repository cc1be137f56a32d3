#include "dpc/scenario_io/scenario_text.h"

#include <unistd.h>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

namespace pb = google::protobuf;
using ::testing::HasSubstr;

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

ScenarioConfig FromText(const std::string& text) {
  return ScenarioFromProto(ParseScenarioText(text, "test.pbtxt"));
}

/// The error parsing and converting `text` raises, or nullopt.
std::optional<ScenarioError> ErrorOf(const std::string& text) {
  try {
    FromText(text);
  } catch (const ScenarioError& e) {
    return e;
  }
  return std::nullopt;
}

// ---- Field-by-field comparison (exact: text format round-trips doubles).

void ExpectSameRange(const std::optional<ControlRange>& a, const std::optional<ControlRange>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_EQ(a->min, b->min);
  EXPECT_EQ(a->max, b->max);
}

void ExpectSameMap(const ControlMapConfig& a, const ControlMapConfig& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.rad_per_unit, b.rad_per_unit);
  EXPECT_EQ(a.offset_rad, b.offset_rad);
  EXPECT_EQ(a.coefficients_rad, b.coefficients_rad);
  EXPECT_EQ(a.table_control, b.table_control);
  EXPECT_EQ(a.table_angle_rad, b.table_angle_rad);
}

void ExpectSameAngle(const StageAngleConfig& a, const StageAngleConfig& b) {
  EXPECT_EQ(a.controlled, b.controlled);
  EXPECT_EQ(a.fixed_rad, b.fixed_rad);
  ExpectSameMap(a.map, b.map);
  ExpectSameRange(a.range, b.range);
}

void ExpectSameScenario(const ScenarioConfig& a, const ScenarioConfig& b) {
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
}

// ---------------------------------------------------------------------------------------------
// Defaults.

TEST(ScenarioTextTest, EmptyTextTakesEveryDefault) {
  const ScenarioConfig config = FromText("");
  ExpectSameScenario(config, ScenarioConfig{});
  EXPECT_EQ(config.name, "paper");
  EXPECT_TRUE(config.stages.empty());
  EXPECT_TRUE(config.input.disturbances.empty());
  EXPECT_EQ(config.controller.method, ControlMethod::kGradientProjection);
  EXPECT_EQ(config.simulation.sample_rate_hz, 50e6);
  EXPECT_FALSE(config.simulation.statistics_start_s.has_value());
}

TEST(ScenarioTextTest, EmptyMessagesTakeTheirDefaults) {
  const ScenarioConfig config = FromText(
      "stages {} input { disturbances { paper_scrambler {} } "
      "disturbances { constant_rotation {} } disturbances { transient_burst {} } } "
      "target {} controller { dither {} } simulation {}");
  ASSERT_EQ(config.stages.size(), 1u);
  EXPECT_EQ(config.stages[0].kind, StageConfig::Kind::kFixedAxis);
  EXPECT_EQ(config.stages[0].axis, Vector3::UnitX());
  EXPECT_EQ(config.stages[0].map.kind, ControlMapConfig::Kind::kLinear);
  EXPECT_EQ(config.stages[0].map.rad_per_unit, M_PI);
  ASSERT_EQ(config.input.disturbances.size(), 3u);
  const DisturbanceConfig& scrambler = config.input.disturbances[0];
  EXPECT_EQ(scrambler.rate_rad_per_s, 1e5);
  EXPECT_EQ(scrambler.kick_rms_ratio, 1.0);
  EXPECT_EQ(scrambler.axis, Vector3::UnitZ());
  EXPECT_EQ(scrambler.kick_axis, Vector3::UnitY());
  EXPECT_EQ(config.input.disturbances[1].rate_rad_per_s, 1e5);
  EXPECT_EQ(config.input.disturbances[1].axis, Vector3::UnitZ());
  const DisturbanceConfig& burst = config.input.disturbances[2];
  EXPECT_EQ(burst.rate_rad_per_s, 1e5);
  EXPECT_EQ(burst.axis, Vector3::UnitZ());
  EXPECT_EQ(burst.envelope, DisturbanceConfig::Envelope::kHalfSine);
  EXPECT_FALSE(burst.random_axis);
  EXPECT_EQ(config.target.kind, TargetConfig::Kind::kPoint);
  EXPECT_EQ(config.target.point, StokesVector(0.0, 0.6, 0.8));
  EXPECT_EQ(config.controller.dither.amplitude, 0.02);
  EXPECT_EQ(config.controller.dither.settle_samples, 0);
  EXPECT_EQ(config.controller.dither.reset_duration_s, 1e-6);
}

TEST(ScenarioTextTest, UnspecifiedEnumsTakeTheFieldsDefault) {
  const ScenarioConfig config = FromText(
      "stages { axis: AXIS_UNSPECIFIED } "
      "input { disturbances { paper_scrambler { rotation_axis: AXIS_UNSPECIFIED "
      "kick_axis: AXIS_UNSPECIFIED } } "
      "disturbances { transient_burst { envelope: ENVELOPE_UNSPECIFIED axis: AXIS_UNSPECIFIED "
      "} } } controller { method: METHOD_UNSPECIFIED loop: LOOP_MODE_UNSPECIFIED }");
  EXPECT_EQ(config.stages[0].axis, Vector3::UnitX());
  EXPECT_EQ(config.input.disturbances[0].axis, Vector3::UnitZ());
  EXPECT_EQ(config.input.disturbances[0].kick_axis, Vector3::UnitY());
  EXPECT_EQ(config.input.disturbances[1].envelope, DisturbanceConfig::Envelope::kHalfSine);
  EXPECT_EQ(config.input.disturbances[1].axis, Vector3::UnitZ());
  EXPECT_EQ(config.controller.method, ControlMethod::kGradientProjection);
  EXPECT_EQ(config.controller.loop, LoopMode::kModel);
}

TEST(ScenarioTextTest, UnsetStageAngleIsFixedAtZero) {
  const ScenarioConfig config =
      FromText("stages { adjustable_axis { orientation { controlled {} } } }");
  ASSERT_EQ(config.stages.size(), 1u);
  EXPECT_EQ(config.stages[0].kind, StageConfig::Kind::kAdjustableAxis);
  EXPECT_FALSE(config.stages[0].retardance.controlled);
  EXPECT_EQ(config.stages[0].retardance.fixed_rad, 0.0);
  EXPECT_TRUE(config.stages[0].orientation.controlled);
  EXPECT_EQ(config.stages[0].orientation.map.rad_per_unit, M_PI);
  EXPECT_FALSE(config.stages[0].orientation.range.has_value());
}

TEST(ScenarioTextTest, UnsetSetNormalIsS3) {
  const ScenarioConfig config = FromText("target { set { offset: 0.5 } }");
  EXPECT_EQ(config.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(config.target.normal, Vector3::UnitZ());
  EXPECT_EQ(config.target.offset, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Every oneof branch.

TEST(ScenarioTextTest, StageAxisBranches) {
  const ScenarioConfig config = FromText(
      "stages { axis: S2 } stages { axis_vector { s1: 0 s2: 3 s3: 4 } } stages { axis: S3 }");
  EXPECT_EQ(config.stages[0].axis, Vector3::UnitY());
  EXPECT_EQ(config.stages[1].axis, Vector3(0.0, 3.0, 4.0));  // normalized by the builder
  EXPECT_EQ(config.stages[2].axis, Vector3::UnitZ());
}

TEST(ScenarioTextTest, MapAndRangeBranches) {
  const ScenarioConfig config = FromText(kFixedAxisText);
  ASSERT_EQ(config.stages.size(), 3u);
  EXPECT_EQ(config.stages[0].name, "vector");
  EXPECT_EQ(config.stages[0].axis, Vector3(0.1, 0.2, 0.9));
  EXPECT_EQ(config.stages[0].map.kind, ControlMapConfig::Kind::kLinear);
  EXPECT_EQ(config.stages[0].map.rad_per_unit, 3.1);
  EXPECT_EQ(config.stages[0].map.offset_rad, 0.2);
  ASSERT_TRUE(config.stages[0].range.has_value());
  EXPECT_EQ(config.stages[0].range->min, -2.0);
  EXPECT_EQ(config.stages[0].range->max, 2.0);
  EXPECT_EQ(config.stages[1].map.kind, ControlMapConfig::Kind::kPolynomial);
  EXPECT_EQ(config.stages[1].map.coefficients_rad, (std::vector<double>{0.1, 3.0, 0.2}));
  EXPECT_FALSE(config.stages[1].range.has_value());
  EXPECT_EQ(config.stages[2].map.kind, ControlMapConfig::Kind::kTable);
  EXPECT_EQ(config.stages[2].map.table_control, (std::vector<double>{-1, 0.25, 1}));
  EXPECT_EQ(config.stages[2].map.table_angle_rad, (std::vector<double>{-3, 0.5, 3}));
}

TEST(ScenarioTextTest, StageAngleBranches) {
  const ScenarioConfig config = FromText(kAdjustableAxisText);
  ASSERT_EQ(config.stages.size(), 3u);
  const StageConfig& qwp = config.stages[0];
  EXPECT_EQ(qwp.name, "qwp");
  EXPECT_EQ(qwp.kind, StageConfig::Kind::kAdjustableAxis);
  EXPECT_FALSE(qwp.retardance.controlled);
  EXPECT_EQ(qwp.retardance.fixed_rad, 1.57);
  EXPECT_TRUE(qwp.orientation.controlled);
  EXPECT_EQ(qwp.orientation.map.rad_per_unit, 2.0);
  EXPECT_EQ(qwp.orientation.map.offset_rad, 0.1);
  ASSERT_TRUE(qwp.orientation.range.has_value());
  EXPECT_EQ(qwp.orientation.range->min, -1.0);
  EXPECT_EQ(config.stages[1].retardance.map.kind, ControlMapConfig::Kind::kTable);
  EXPECT_EQ(config.stages[1].orientation.fixed_rad, 0.3);
  EXPECT_EQ(config.stages[2].retardance.map.kind, ControlMapConfig::Kind::kPolynomial);
  EXPECT_TRUE(config.stages[2].orientation.controlled);
  EXPECT_EQ(ScenarioControlCount(config.stages), 4);
}

TEST(ScenarioTextTest, DisturbanceBranches) {
  const ScenarioConfig config = FromText(kFixedAxisText);
  ASSERT_EQ(config.input.disturbances.size(), 4u);
  const auto& d = config.input.disturbances;
  EXPECT_EQ(d[0].kind, DisturbanceConfig::Kind::kPaperScrambler);
  EXPECT_EQ(d[0].rate_rad_per_s, 2e5);
  EXPECT_EQ(d[0].kick_rms_ratio, 0.5);
  EXPECT_EQ(d[0].axis, Vector3(0.1, 0.2, 1.0));
  EXPECT_EQ(d[0].kick_axis, Vector3(0.3, 1.0, 0.1));
  EXPECT_EQ(d[1].kind, DisturbanceConfig::Kind::kRandomWalk);
  EXPECT_EQ(d[1].diffusion_rad_per_sqrt_s, 10.0);
  EXPECT_EQ(d[2].kind, DisturbanceConfig::Kind::kConstantRotation);
  EXPECT_EQ(d[2].rate_rad_per_s, 1e4);
  EXPECT_EQ(d[2].axis, Vector3(1.0, 0.5, 0.25));
  EXPECT_EQ(d[3].kind, DisturbanceConfig::Kind::kTransientBurst);
  EXPECT_EQ(d[3].start_s, 1e-3);
  EXPECT_EQ(d[3].duration_s, 1e-4);
  EXPECT_EQ(d[3].rate_rad_per_s, 5e6);
  EXPECT_EQ(d[3].period_s, 2e-3);
  EXPECT_EQ(d[3].envelope, DisturbanceConfig::Envelope::kRectangular);
  EXPECT_EQ(d[3].axis, Vector3(0.5, 0.5, 0.5));
  EXPECT_FALSE(d[3].random_axis);
}

TEST(ScenarioTextTest, ElementalDisturbanceAxesAndRandomAxis) {
  const ScenarioConfig config = FromText(
      "input { disturbances { paper_scrambler { rotation_axis: S1 kick_axis: S3 } } "
      "disturbances { constant_rotation { axis: S2 } } "
      "disturbances { transient_burst { axis: S1 envelope: HALF_SINE } } "
      "disturbances { transient_burst { random_axis: true } } }");
  const auto& d = config.input.disturbances;
  ASSERT_EQ(d.size(), 4u);
  EXPECT_EQ(d[0].axis, Vector3::UnitX());
  EXPECT_EQ(d[0].kick_axis, Vector3::UnitZ());
  EXPECT_EQ(d[1].axis, Vector3::UnitY());
  EXPECT_EQ(d[2].axis, Vector3::UnitX());
  EXPECT_EQ(d[2].envelope, DisturbanceConfig::Envelope::kHalfSine);
  EXPECT_TRUE(d[3].random_axis);
}

TEST(ScenarioTextTest, TargetBranches) {
  EXPECT_EQ(FromText(kFixedAxisText).target.point, StokesVector(0.48, 0.6, 0.64));
  const ScenarioConfig config = FromText(kAdjustableAxisText);
  EXPECT_EQ(config.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(config.target.normal, Vector3(0.1, 0.2, 1.0));
  EXPECT_EQ(config.target.offset, 0.3);
}

TEST(ScenarioTextTest, ControllerAndSimulationFields) {
  const ScenarioConfig config = FromText(kFixedAxisText);
  const ControllerConfig& c = config.controller;
  EXPECT_EQ(c.method, ControlMethod::kPseudoInverse);
  EXPECT_EQ(c.step, 0.2);
  EXPECT_EQ(c.nullspace_step, 0.05);
  EXPECT_EQ(c.threshold, 0.9);
  EXPECT_EQ(c.damping, 2e-3);
  EXPECT_EQ(c.singular_value_tolerance, 1e-10);
  EXPECT_EQ(c.loop, LoopMode::kMeasured);
  EXPECT_EQ(c.activation_s, 1e-3);
  EXPECT_EQ(c.initial_phi, (std::vector<double>{0.1, 0.2, 0.3}));
  EXPECT_EQ(c.dither.amplitude, 0.01);
  EXPECT_EQ(c.dither.settle_samples, 3);
  EXPECT_EQ(c.dither.reset_threshold, 0.8);
  EXPECT_EQ(c.dither.reset_duration_s, 2e-6);
  const SimulationConfig& s = config.simulation;
  EXPECT_EQ(s.sample_rate_hz, 40e6);
  EXPECT_EQ(s.delay_s, 0.5e-6);
  EXPECT_EQ(s.duration_s, 4e-3);
  EXPECT_EQ(s.polarimeter_noise_deg, 0.5);
  EXPECT_EQ(s.seed, 3u);
  EXPECT_EQ(s.lock_threshold_deg, 5.0);
  EXPECT_EQ(s.statistics_start_s, std::optional<double>(3e-3));
}

TEST(ScenarioTextTest, EveryMethodName) {
  const std::vector<std::pair<std::string, ControlMethod>> methods = {
      {"INVERSE", ControlMethod::kInverse},
      {"TRANSPOSE", ControlMethod::kTranspose},
      {"DAMPED", ControlMethod::kDamped},
      {"PINV", ControlMethod::kPseudoInverse},
      {"RLS", ControlMethod::kRegularizedLeastSquares},
      {"GP", ControlMethod::kGradientProjection},
      {"GPT", ControlMethod::kThresholdedGradientProjection},
      {"EXTENDED", ControlMethod::kExtendedJacobian},
      {"DITHER", ControlMethod::kDither}};
  for (const auto& [name, method] : methods) {
    EXPECT_EQ(FromText("controller { method: " + name + " }").controller.method, method) << name;
  }
}

TEST(ScenarioTextTest, TheExampleTextsAreValid) {
  EXPECT_NO_THROW(ValidateScenario(FromText(kFixedAxisText)));
  EXPECT_NO_THROW(ValidateScenario(FromText(kAdjustableAxisText)));
}

// ---------------------------------------------------------------------------------------------
// Parse errors: "source:line:column" with protobuf's message. Protobuf places an error at the
// token after the offending one (the value is read before it is looked up), so a bad value at
// the end of a line is reported at the start of the next token.

TEST(ScenarioTextTest, UnknownMethodNamesLineAndColumn) {
  const auto error = ErrorOf("name: \"x\"\ncontroller { method: FOO step: 0.1 }\n");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:2:26");  // just after FOO
  EXPECT_THAT(error->message(), HasSubstr("method"));
  EXPECT_THAT(error->message(), HasSubstr("FOO"));
}

TEST(ScenarioTextTest, UnknownFieldIsAParseError) {
  EXPECT_THROW(FromText("controller { stpe: 0.1 }"), ScenarioError);
  const auto error = ErrorOf("controller { stpe: 0.1 }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:1:18");  // just after stpe
  EXPECT_THAT(error->message(), HasSubstr("stpe"));
}

TEST(ScenarioTextTest, SyntaxErrorIsAParseError) {
  const auto error = ErrorOf("stages {\n  axis: S1\n");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::StartsWith("test.pbtxt:"));
}

TEST(ScenarioTextTest, RepeatedSingularFieldIsAParseError) {
  const auto error = ErrorOf("controller {\n  step: 0.1\n  step: 0.2\n}");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:3:7");
  EXPECT_THAT(error->message(), HasSubstr("step"));
}

TEST(ScenarioTextTest, TwoMembersOfAOneofAreAParseError) {
  const auto error = ErrorOf("stages { map { linear {} polynomial {} } }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::StartsWith("test.pbtxt:1:"));
  EXPECT_THAT(error->message(), HasSubstr("polynomial"));
}

TEST(ScenarioTextTest, UndefinedEnumNumberIsNamed) {
  // proto3 enums are open: the parser keeps a number it does not know; the conversion names it.
  const auto error = ErrorOf("controller { method: 42 }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::AnyOf("controller.method", "test.pbtxt:1:22"));
  EXPECT_THAT(error->message(), HasSubstr("42"));
}

TEST(ScenarioTextTest, UndefinedAxisNumberIsNamed) {
  const auto error = ErrorOf("stages {} stages { axis: 7 }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::AnyOf("stages[1].axis", "test.pbtxt:1:26"));
}

TEST(ScenarioTextTest, OversizedTextIsRejected) {
  const std::string text(kMaxScenarioTextBytes + 1, ' ');
  EXPECT_THROW(ParseScenarioText(text, "big.pbtxt"), ScenarioError);
}

// ---------------------------------------------------------------------------------------------
// Structural conflicts, named by field.

TEST(ScenarioTextTest, StageWithAnAxisAndAdjustableAxisIsRejected) {
  const auto error = ErrorOf(
      "stages { axis: S1 } stages { axis: S3 adjustable_axis { orientation { controlled {} } } }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages[1].adjustable_axis");
  EXPECT_THAT(error->message(), HasSubstr("axis"));
}

TEST(ScenarioTextTest, StageWithAMapAndAdjustableAxisIsRejected) {
  const auto error = ErrorOf(
      "stages { map { linear {} } adjustable_axis { orientation { controlled {} } } }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages[0].adjustable_axis");
  EXPECT_THAT(error->message(), HasSubstr("map"));
}

TEST(ScenarioTextTest, DisturbanceWithoutAKindIsRejected) {
  const auto error = ErrorOf("input { disturbances { random_walk {} } disturbances {} }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "input.disturbances[1]");
}

// ---------------------------------------------------------------------------------------------
// Round trips.

TEST(ScenarioTextTest, PaperScenarioRoundTrips) {
  const ScenarioConfig paper = PaperScenario("3131");
  ExpectSameScenario(ScenarioFromProto(ScenarioToProto(paper)), paper);
  ExpectSameScenario(FromText(ScenarioToText(paper)), paper);
}

TEST(ScenarioTextTest, EveryFieldRoundTrips) {
  for (const char* text : {kFixedAxisText, kAdjustableAxisText}) {
    const ScenarioConfig config = FromText(text);
    SCOPED_TRACE(config.name);
    ExpectSameScenario(ScenarioFromProto(ScenarioToProto(config)), config);
    ExpectSameScenario(FromText(ScenarioToText(config)), config);
  }
}

TEST(ScenarioTextTest, DoublesRoundTripExactly) {
  ScenarioConfig config = PaperScenario("131");
  config.controller.step = 0.1 + 0.2;
  config.stages[0].map.rad_per_unit = 1.0 / 3.0;
  config.stages[1].axis = Vector3(std::sqrt(2.0), -1e-300, 1e300);
  config.simulation.statistics_start_s = std::nextafter(5e-3, 1.0);
  ExpectSameScenario(FromText(ScenarioToText(config)), config);
}

TEST(ScenarioTextTest, TextNamesElementalAxesByEnum) {
  const std::string text = ScenarioToText(PaperScenario("131"));
  EXPECT_THAT(text, HasSubstr("axis: S1"));
  EXPECT_THAT(text, HasSubstr("axis: S3"));
  EXPECT_THAT(text, HasSubstr("method: GP"));
}

// ---------------------------------------------------------------------------------------------
// Files.

class ScenarioTextFileTest : public ::testing::Test {
 protected:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  void Write(const std::string& text) {
    std::ofstream file(path_, std::ios::binary);
    file << text;
  }
  std::optional<ScenarioError> LoadError() const {
    try {
      LoadScenarioFile(path_);
    } catch (const ScenarioError& e) {
      return e;
    }
    return std::nullopt;
  }

  // Unique per process: several worktrees may run the suite at once.
  const std::string path_ =
      fmt::format("{}scenario_text_test_{}.pbtxt", ::testing::TempDir(), ::getpid());
};

TEST_F(ScenarioTextFileTest, LoadsAndValidates) {
  Write(ScenarioToText(PaperScenario("131")));
  const ScenarioConfig config = LoadScenarioFile(path_);
  ExpectSameScenario(config, PaperScenario("131"));
}

TEST_F(ScenarioTextFileTest, MissingFileIsLocatedAtThePath) {
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
}

TEST_F(ScenarioTextFileTest, DirectoryIsRejected) {
  EXPECT_THROW(LoadScenarioFile(::testing::TempDir()), ScenarioError);
}

TEST_F(ScenarioTextFileTest, AFifoIsRefusedWithoutBlocking) {
  // Opening a FIFO for reading blocks until a writer comes; a service reading one at start-up
  // would hang and ignore SIGTERM.
  ASSERT_EQ(::mkfifo(path_.c_str(), 0600), 0);
  const auto error = LoadError();
  ::unlink(path_.c_str());
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
  EXPECT_THAT(error->message(), HasSubstr("not a regular file"));
}

TEST_F(ScenarioTextFileTest, OversizedFileIsLocatedAtThePath) {
  Write(std::string(kMaxScenarioTextBytes + 1, '\n'));
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
  EXPECT_THAT(error->message(), HasSubstr("16 MiB"));
}

TEST_F(ScenarioTextFileTest, ParseErrorIsLocatedInTheFile) {
  Write("stages { axis: S1 }\ncontroller { method: FOO }\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_ + ":2:26");  // just after FOO
}

TEST_F(ScenarioTextFileTest, InvalidValueIsLocatedByField) {
  Write("stages { axis: S1 }\ncontroller { step: -0.1 }\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "controller.step");
}

TEST_F(ScenarioTextFileTest, StagelessFileIsRejected) {
  Write("name: \"nothing\"\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages");
}

// ---------------------------------------------------------------------------------------------
// A non-finite value in any double field is reported at that field's path. Driven by
// reflection over scenario.proto, so that a double field added to the schema without
// validation (or without a value in the example texts) fails here.

/// One step of a field path: a field, and an element index for repeated fields (−1 otherwise).
struct PathStep {
  const pb::FieldDescriptor* field;
  int index;
};
using FieldPath = std::vector<PathStep>;

std::string PathText(const FieldPath& path) {
  std::string text;
  for (const PathStep& step : path) {
    if (!text.empty()) text += '.';
    text += step.field->name();
    if (step.index >= 0) text += fmt::format("[{}]", step.index);
  }
  return text;
}

/// Every double value present in `message` (ListFields: set fields, non-empty repeated ones),
/// recursively.
void CollectPresentDoubles(const pb::Message& message, FieldPath* prefix,
                           std::vector<FieldPath>* out) {
  const pb::Reflection* reflection = message.GetReflection();
  std::vector<const pb::FieldDescriptor*> fields;
  reflection->ListFields(message, &fields);
  for (const pb::FieldDescriptor* field : fields) {
    const int count = field->is_repeated() ? reflection->FieldSize(message, field) : 1;
    for (int i = 0; i < count; ++i) {
      prefix->push_back({field, field->is_repeated() ? i : -1});
      if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE) {
        out->push_back(*prefix);
      } else if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
        CollectPresentDoubles(field->is_repeated()
                                  ? reflection->GetRepeatedMessage(message, field, i)
                                  : reflection->GetMessage(message, field),
                              prefix, out);
      }
      prefix->pop_back();
    }
  }
}

void SetDoubleAt(pb::Message* message, const FieldPath& path, double value) {
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const pb::Reflection* reflection = message->GetReflection();
    message = path[k].index >= 0
                  ? reflection->MutableRepeatedMessage(message, path[k].field, path[k].index)
                  : reflection->MutableMessage(message, path[k].field);
  }
  const PathStep& last = path.back();
  if (last.index >= 0) {
    message->GetReflection()->SetRepeatedDouble(message, last.field, last.index, value);
  } else {
    message->GetReflection()->SetDouble(message, last.field, value);
  }
}

/// The full names of every double field reachable from `descriptor`.
void CollectSchemaDoubles(const pb::Descriptor* descriptor, std::set<const pb::Descriptor*>* seen,
                          std::set<std::string>* out) {
  if (!seen->insert(descriptor).second) return;
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const pb::FieldDescriptor* field = descriptor->field(i);
    if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE) out->insert(field->full_name());
    if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
      CollectSchemaDoubles(field->message_type(), seen, out);
    }
  }
}

TEST(ScenarioTextNonFiniteTest, EveryDoubleFieldIsValidatedAtItsPath) {
  std::set<std::string> covered;
  int cases = 0;
  for (const char* text : {kFixedAxisText, kAdjustableAxisText}) {
    const scenario::Scenario valid = ParseScenarioText(text, "test.pbtxt");
    ASSERT_NO_THROW(ValidateScenario(ScenarioFromProto(valid)));
    std::vector<FieldPath> doubles;
    FieldPath prefix;
    CollectPresentDoubles(valid, &prefix, &doubles);
    for (const FieldPath& path : doubles) {
      covered.insert(path.back().field->full_name());
      for (double bad : {std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity(),
                         -std::numeric_limits<double>::infinity()}) {
        scenario::Scenario broken = valid;
        SetDoubleAt(&broken, path, bad);
        const std::string expected = PathText(path);
        SCOPED_TRACE(expected + " = " + std::to_string(bad));
        ++cases;
        try {
          ValidateScenario(ScenarioFromProto(broken));
          ADD_FAILURE() << "accepted";
        } catch (const ScenarioError& e) {
          EXPECT_EQ(e.location(), expected) << e.what();
        }
      }
    }
  }
  EXPECT_GT(cases, 100);

  std::set<std::string> schema;
  std::set<const pb::Descriptor*> seen;
  CollectSchemaDoubles(scenario::Scenario::descriptor(), &seen, &schema);
  EXPECT_EQ(covered, schema) << "every double field of scenario.proto needs a non-zero value in "
                                "one of the example texts (and validation)";
  EXPECT_GE(schema.size(), 36u);  // as of writing; more is fine
}

}  // namespace
}  // namespace dpc
