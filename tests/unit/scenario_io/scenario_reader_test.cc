#include "dpc/scenario_io/scenario_reader.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "dpc/config/scenario_validation.h"
#include "support/scenario_texts.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using namespace dpc::testing;

TEST(ScenarioReaderTest, EmptyTextTakesEveryDefault) {
  const ScenarioConfig config = FromText("");
  ExpectSameScenario(config, ScenarioConfig{});
  EXPECT_EQ(config.name, "paper");
  EXPECT_TRUE(config.stages.empty());
  EXPECT_TRUE(config.input.disturbances.empty());
  EXPECT_EQ(config.controller.method, ControlMethod::kGradientProjection);
  EXPECT_EQ(config.simulation.sample_rate_hz, 50e6);
  EXPECT_FALSE(config.simulation.statistics_start_s.has_value());
}

TEST(ScenarioReaderTest, EmptyMessagesTakeTheirDefaults) {
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

TEST(ScenarioReaderTest, UnspecifiedEnumsTakeTheFieldsDefault) {
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

TEST(ScenarioReaderTest, UnsetStageAngleIsFixedAtZero) {
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

TEST(ScenarioReaderTest, UnsetSetNormalIsS3) {
  const ScenarioConfig config = FromText("target { set { offset: 0.5 } }");
  EXPECT_EQ(config.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(config.target.normal, Vector3::UnitZ());
  EXPECT_EQ(config.target.offset, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Every oneof branch.

TEST(ScenarioReaderTest, StageAxisBranches) {
  const ScenarioConfig config = FromText(
      "stages { axis: S2 } stages { axis_vector { s1: 0 s2: 3 s3: 4 } } stages { axis: S3 }");
  EXPECT_EQ(config.stages[0].axis, Vector3::UnitY());
  EXPECT_EQ(config.stages[1].axis, Vector3(0.0, 3.0, 4.0));  // normalized by the builder
  EXPECT_EQ(config.stages[2].axis, Vector3::UnitZ());
}

TEST(ScenarioReaderTest, MapAndRangeBranches) {
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

TEST(ScenarioReaderTest, TablesByConditionAreReadWithTheirKey) {
  const ScenarioConfig config = FromText(kConditionTablesText);
  ASSERT_EQ(config.stages.size(), 3u);
  const ControlMapConfig& by_temperature = config.stages[0].map;
  EXPECT_EQ(by_temperature.kind, ControlMapConfig::Kind::kTablesByCondition);
  EXPECT_EQ(by_temperature.condition, ControlMapConfig::Condition::kTemperatureC);
  EXPECT_EQ(by_temperature.operating_point, 30.0);
  ASSERT_EQ(by_temperature.condition_tables.size(), 2u);
  EXPECT_EQ(by_temperature.condition_tables[1].condition, 35.0);
  EXPECT_EQ(by_temperature.condition_tables[1].control, (std::vector<double>{-1, 0.5, 1}));
  EXPECT_EQ(by_temperature.condition_tables[1].angle_rad, (std::vector<double>{-3.2, 1.6, 3.2}));
  const ControlMapConfig& by_wavelength = config.stages[2].orientation.map;
  EXPECT_EQ(by_wavelength.kind, ControlMapConfig::Kind::kTablesByCondition);
  EXPECT_EQ(by_wavelength.condition, ControlMapConfig::Condition::kWavelengthNm);
  EXPECT_EQ(by_wavelength.operating_point, 1550.0);
  EXPECT_EQ(by_wavelength.condition_tables[0].condition, 1500.0);
  EXPECT_NO_THROW(ValidateScenario(config));
}

TEST(ScenarioReaderTest, TablesByConditionNeedOneKeyAndAnOperatingPoint) {
  const auto error = ErrorOf(R"pb(stages { map { tables_by_condition {
      operating_temperature_c: 20
      tables { temperature_c: 10 table { control: [ 0, 1 ] angle_rad: [ 0, 1 ] } }
      tables { wavelength_nm: 1550 table { control: [ 0, 1 ] angle_rad: [ 0, 1 ] } } } } })pb");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages[0].map.tables_by_condition.tables[1]");
  EXPECT_THAT(error->message(), HasSubstr("every table needs its temperature_c"));
  const auto unkeyed = ErrorOf(R"pb(stages { map { tables_by_condition {
      operating_wavelength_nm: 1550 tables { table { control: [ 0, 1 ] angle_rad: [ 0, 1 ] } } } } })pb");
  ASSERT_TRUE(unkeyed);
  EXPECT_EQ(unkeyed->location(), "stages[0].map.tables_by_condition.tables[0]");
  EXPECT_THAT(unkeyed->message(), HasSubstr("no condition"));
  const auto no_point = ErrorOf(R"pb(stages { adjustable_axis { retardance { controlled { map {
      tables_by_condition { tables { temperature_c: 10 table { control: [ 0, 1 ] angle_rad: [ 0, 1 ] } } } } } } } })pb");
  ASSERT_TRUE(no_point);
  EXPECT_EQ(no_point->location(), "stages[0].adjustable_axis.retardance.controlled.map.tables_by_condition");
  EXPECT_THAT(no_point->message(), HasSubstr("no operating point"));
}

TEST(ScenarioReaderTest, StageAngleBranches) {
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

TEST(ScenarioReaderTest, DisturbanceBranches) {
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

TEST(ScenarioReaderTest, ElementalDisturbanceAxesAndRandomAxis) {
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

TEST(ScenarioReaderTest, TargetBranches) {
  EXPECT_EQ(FromText(kFixedAxisText).target.point, StokesVector(0.48, 0.6, 0.64));
  const ScenarioConfig config = FromText(kAdjustableAxisText);
  EXPECT_EQ(config.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(config.target.normal, Vector3(0.1, 0.2, 1.0));
  EXPECT_EQ(config.target.offset, 0.3);
}

TEST(ScenarioReaderTest, ControllerAndSimulationFields) {
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

TEST(ScenarioReaderTest, EveryMethodName) {
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

TEST(ScenarioReaderTest, TheExampleTextsAreValid) {
  EXPECT_NO_THROW(ValidateScenario(FromText(kFixedAxisText)));
  EXPECT_NO_THROW(ValidateScenario(FromText(kAdjustableAxisText)));
}

// ---------------------------------------------------------------------------------------------
// Parse errors: "source:line:column" with protobuf's message. Protobuf places an error at the
// token after the offending one (the value is read before it is looked up), so a bad value at
// the end of a line is reported at the start of the next token.

TEST(ScenarioReaderTest, UnknownMethodNamesLineAndColumn) {
  const auto error = ErrorOf("name: \"x\"\ncontroller { method: FOO step: 0.1 }\n");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:2:26");  // just after FOO
  EXPECT_THAT(error->message(), HasSubstr("method"));
  EXPECT_THAT(error->message(), HasSubstr("FOO"));
}

TEST(ScenarioReaderTest, UnknownFieldIsAParseError) {
  EXPECT_THROW(FromText("controller { stpe: 0.1 }"), ScenarioError);
  const auto error = ErrorOf("controller { stpe: 0.1 }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:1:18");  // just after stpe
  EXPECT_THAT(error->message(), HasSubstr("stpe"));
}

TEST(ScenarioReaderTest, SyntaxErrorIsAParseError) {
  const auto error = ErrorOf("stages {\n  axis: S1\n");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::StartsWith("test.pbtxt:"));
}

TEST(ScenarioReaderTest, RepeatedSingularFieldIsAParseError) {
  const auto error = ErrorOf("controller {\n  step: 0.1\n  step: 0.2\n}");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "test.pbtxt:3:7");
  EXPECT_THAT(error->message(), HasSubstr("step"));
}

TEST(ScenarioReaderTest, TwoMembersOfAOneofAreAParseError) {
  const auto error = ErrorOf("stages { map { linear {} polynomial {} } }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::StartsWith("test.pbtxt:1:"));
  EXPECT_THAT(error->message(), HasSubstr("polynomial"));
}

TEST(ScenarioReaderTest, UndefinedEnumNumberIsNamed) {
  // proto3 enums are open: the parser keeps a number it does not know; the conversion names it.
  const auto error = ErrorOf("controller { method: 42 }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::AnyOf("controller.method", "test.pbtxt:1:22"));
  EXPECT_THAT(error->message(), HasSubstr("42"));
}

TEST(ScenarioReaderTest, UndefinedAxisNumberIsNamed) {
  const auto error = ErrorOf("stages {} stages { axis: 7 }");
  ASSERT_TRUE(error);
  EXPECT_THAT(error->location(), ::testing::AnyOf("stages[1].axis", "test.pbtxt:1:26"));
}

TEST(ScenarioReaderTest, OversizedTextIsRejected) {
  const std::string text(kMaxScenarioTextBytes + 1, ' ');
  EXPECT_THROW(ParseScenarioText(text, "big.pbtxt"), ScenarioError);
}

// ---------------------------------------------------------------------------------------------
// Structural conflicts, named by field.

TEST(ScenarioReaderTest, StageWithAnAxisAndAdjustableAxisIsRejected) {
  const auto error = ErrorOf(
      "stages { axis: S1 } stages { axis: S3 adjustable_axis { orientation { controlled {} } } }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages[1].adjustable_axis");
  EXPECT_THAT(error->message(), HasSubstr("axis"));
}

TEST(ScenarioReaderTest, StageWithAMapAndAdjustableAxisIsRejected) {
  const auto error = ErrorOf(
      "stages { map { linear {} } adjustable_axis { orientation { controlled {} } } }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages[0].adjustable_axis");
  EXPECT_THAT(error->message(), HasSubstr("map"));
}

TEST(ScenarioReaderTest, DisturbanceWithoutAKindIsRejected) {
  const auto error = ErrorOf("input { disturbances { random_walk {} } disturbances {} }");
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "input.disturbances[1]");
}

}  // namespace
}  // namespace dpc
