#include "dpc/scenario_io/scenario_reader.h"

#include <fmt/format.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <optional>
#include <utility>

#include "dpc/config/scenario_builders.h"

namespace dpc {
namespace {

namespace pb = google::protobuf;

// ---------------------------------------------------------------------------------------------
// Parsing.

/// Keeps the first error the parser reports, with 1-based line and column.
class FirstErrorCollector final : public pb::io::ErrorCollector {
 public:
  void AddError(int line, pb::io::ColumnNumber column, const std::string& message) override {
    if (error_) return;
    error_ = Error{line, column, message};
  }

  struct Error {
    int line;    ///< 0-based; −1 when the parser has no position
    int column;  ///< 0-based
    std::string message;
  };
  const std::optional<Error>& error() const { return error_; }

 private:
  std::optional<Error> error_;
};

// ---------------------------------------------------------------------------------------------
// Proto → config.

/// "INVERSE, TRANSPOSE, …" for an enum, without its *_UNSPECIFIED value.
std::string EnumNames(const pb::EnumDescriptor* descriptor) {
  std::string names;
  for (int i = 0; i < descriptor->value_count(); ++i) {
    const pb::EnumValueDescriptor* value = descriptor->value(i);
    if (value->number() == 0) continue;
    if (!names.empty()) names += ", ";
    names += value->name();
  }
  return names;
}

[[noreturn]] void FailEnum(const std::string& path, int number,
                           const pb::EnumDescriptor* descriptor) {
  throw ScenarioError(path, fmt::format("{} is not a value of enum {}; use one of {}", number,
                                        descriptor->name(), EnumNames(descriptor)));
}

Vector3 VectorFromProto(const scenario::Vector3& v) { return Vector3(v.s1(), v.s2(), v.s3()); }

Vector3 AxisFromEnum(scenario::Axis axis, const Vector3& default_axis, const std::string& path) {
  switch (axis) {
    case scenario::AXIS_UNSPECIFIED: return default_axis;
    case scenario::S1: return Vector3::UnitX();
    case scenario::S2: return Vector3::UnitY();
    case scenario::S3: return Vector3::UnitZ();
    default: FailEnum(path, axis, scenario::Axis_descriptor());
  }
}

ConditionTableConfig ConditionTableFromProto(const scenario::TableAtCondition& proto,
                                             ControlMapConfig::Condition condition, const std::string& path) {
  const bool by_temperature = condition == ControlMapConfig::Condition::kTemperatureC;
  const bool has = by_temperature ? proto.condition_case() == scenario::TableAtCondition::kTemperatureC
                                  : proto.condition_case() == scenario::TableAtCondition::kWavelengthNm;
  if (!has) {
    throw ScenarioError(path, fmt::format("{}: the map's operating point is a {}, so every table needs its {}",
                                          proto.condition_case() == scenario::TableAtCondition::CONDITION_NOT_SET
                                              ? "no condition"
                                              : "a condition of the other kind",
                                          ConditionNoun(condition), ConditionKeyName(condition)));
  }
  ConditionTableConfig table;
  table.condition = by_temperature ? proto.temperature_c() : proto.wavelength_nm();
  table.control.assign(proto.table().control().begin(), proto.table().control().end());
  table.angle_rad.assign(proto.table().angle_rad().begin(), proto.table().angle_rad().end());
  return table;
}

ControlMapConfig MapFromProto(const scenario::ControlMap& proto, const std::string& path) {
  ControlMapConfig map;  // unset: linear, π rad per unit
  switch (proto.kind_case()) {
    case scenario::ControlMap::kLinear:
      map.kind = ControlMapConfig::Kind::kLinear;
      if (proto.linear().has_rad_per_unit()) map.rad_per_unit = proto.linear().rad_per_unit();
      map.offset_rad = proto.linear().offset_rad();
      break;
    case scenario::ControlMap::kPolynomial:
      map.kind = ControlMapConfig::Kind::kPolynomial;
      map.coefficients_rad.assign(proto.polynomial().coefficients_rad().begin(),
                                  proto.polynomial().coefficients_rad().end());
      break;
    case scenario::ControlMap::kTable:
      map.kind = ControlMapConfig::Kind::kTable;
      map.table_control.assign(proto.table().control().begin(), proto.table().control().end());
      map.table_angle_rad.assign(proto.table().angle_rad().begin(),
                                 proto.table().angle_rad().end());
      break;
    case scenario::ControlMap::kTablesByCondition: {
      const scenario::TablesByCondition& keyed = proto.tables_by_condition();
      const std::string keyed_path = path + ".tables_by_condition";
      map.kind = ControlMapConfig::Kind::kTablesByCondition;
      switch (keyed.operating_case()) {
        case scenario::TablesByCondition::kOperatingTemperatureC:
          map.condition = ControlMapConfig::Condition::kTemperatureC;
          map.operating_point = keyed.operating_temperature_c();
          break;
        case scenario::TablesByCondition::kOperatingWavelengthNm:
          map.condition = ControlMapConfig::Condition::kWavelengthNm;
          map.operating_point = keyed.operating_wavelength_nm();
          break;
        case scenario::TablesByCondition::OPERATING_NOT_SET:
          throw ScenarioError(keyed_path, "no operating point: set operating_temperature_c or operating_wavelength_nm "
                                          "(the condition the bench runs at)");
      }
      for (int i = 0; i < keyed.tables_size(); ++i) {
        map.condition_tables.push_back(
            ConditionTableFromProto(keyed.tables(i), map.condition, fmt::format("{}.tables[{}]", keyed_path, i)));
      }
      break;
    }
    case scenario::ControlMap::KIND_NOT_SET: break;
  }
  return map;
}

ControlRange RangeFromProto(const scenario::ControlRange& proto) {
  return ControlRange{proto.min(), proto.max()};
}

StageAngleConfig AngleFromProto(const scenario::StageAngle& proto, const std::string& path) {
  StageAngleConfig angle;  // unset: fixed at 0 rad
  switch (proto.kind_case()) {
    case scenario::StageAngle::kFixedRad:
      angle.controlled = false;
      angle.fixed_rad = proto.fixed_rad();
      break;
    case scenario::StageAngle::kControlled:
      angle.controlled = true;
      angle.map = MapFromProto(proto.controlled().map(), path + ".controlled.map");
      if (proto.controlled().has_range()) angle.range = RangeFromProto(proto.controlled().range());
      break;
    case scenario::StageAngle::KIND_NOT_SET: break;
  }
  return angle;
}

StageConfig StageFromProto(const scenario::Stage& proto, const std::string& path) {
  StageConfig stage;  // default axis S1, map linear π rad per unit
  stage.name = proto.name();
  if (proto.has_adjustable_axis()) {
    std::string fixed_fields;
    const auto mention = [&fixed_fields](const char* field) {
      fixed_fields += fixed_fields.empty() ? field : std::string(", ") + field;
    };
    if (proto.axis_kind_case() == scenario::Stage::kAxis) mention("axis");
    if (proto.axis_kind_case() == scenario::Stage::kAxisVector) mention("axis_vector");
    if (proto.has_map()) mention("map");
    if (proto.has_range()) mention("range");
    if (!fixed_fields.empty()) {
      throw ScenarioError(path + ".adjustable_axis",
                          fmt::format("the stage also sets {} of a fixed-axis stage; a stage is "
                                      "either fixed-axis (axis or axis_vector, map, range) or "
                                      "adjustable_axis, not both",
                                      fixed_fields));
    }
    stage.kind = StageConfig::Kind::kAdjustableAxis;
    stage.retardance = AngleFromProto(proto.adjustable_axis().retardance(), path + ".adjustable_axis.retardance");
    stage.orientation = AngleFromProto(proto.adjustable_axis().orientation(), path + ".adjustable_axis.orientation");
    return stage;
  }
  stage.kind = StageConfig::Kind::kFixedAxis;
  switch (proto.axis_kind_case()) {
    case scenario::Stage::kAxis:
      stage.axis = AxisFromEnum(proto.axis(), stage.axis, path + ".axis");
      break;
    case scenario::Stage::kAxisVector: stage.axis = VectorFromProto(proto.axis_vector()); break;
    case scenario::Stage::AXIS_KIND_NOT_SET: break;
  }
  stage.map = MapFromProto(proto.map(), path + ".map");
  if (proto.has_range()) stage.range = RangeFromProto(proto.range());
  return stage;
}

DisturbanceConfig DisturbanceFromProto(const scenario::Disturbance& proto,
                                       const std::string& path) {
  DisturbanceConfig d;  // the struct's defaults are the schema's: 1e5 rad/s, about S3, kicks S2
  switch (proto.kind_case()) {
    case scenario::Disturbance::kPaperScrambler: {
      const scenario::PaperScrambler& p = proto.paper_scrambler();
      const std::string p_path = path + ".paper_scrambler";
      d.kind = DisturbanceConfig::Kind::kPaperScrambler;
      if (p.has_rate_rad_per_s()) d.rate_rad_per_s = p.rate_rad_per_s();
      if (p.has_kick_rms_ratio()) d.kick_rms_ratio = p.kick_rms_ratio();
      switch (p.rotation_case()) {
        case scenario::PaperScrambler::kRotationAxis:
          d.axis = AxisFromEnum(p.rotation_axis(), d.axis, p_path + ".rotation_axis");
          break;
        case scenario::PaperScrambler::kRotationAxisVector:
          d.axis = VectorFromProto(p.rotation_axis_vector());
          break;
        case scenario::PaperScrambler::ROTATION_NOT_SET: break;
      }
      switch (p.kick_case()) {
        case scenario::PaperScrambler::kKickAxis:
          d.kick_axis = AxisFromEnum(p.kick_axis(), d.kick_axis, p_path + ".kick_axis");
          break;
        case scenario::PaperScrambler::kKickAxisVector:
          d.kick_axis = VectorFromProto(p.kick_axis_vector());
          break;
        case scenario::PaperScrambler::KICK_NOT_SET: break;
      }
      return d;
    }
    case scenario::Disturbance::kRandomWalk:
      d.kind = DisturbanceConfig::Kind::kRandomWalk;
      d.diffusion_rad_per_sqrt_s = proto.random_walk().diffusion_rad_per_sqrt_s();
      return d;
    case scenario::Disturbance::kConstantRotation: {
      const scenario::ConstantRotation& p = proto.constant_rotation();
      d.kind = DisturbanceConfig::Kind::kConstantRotation;
      if (p.has_rate_rad_per_s()) d.rate_rad_per_s = p.rate_rad_per_s();
      switch (p.axis_kind_case()) {
        case scenario::ConstantRotation::kAxis:
          d.axis = AxisFromEnum(p.axis(), d.axis, path + ".constant_rotation.axis");
          break;
        case scenario::ConstantRotation::kAxisVector:
          d.axis = VectorFromProto(p.axis_vector());
          break;
        case scenario::ConstantRotation::AXIS_KIND_NOT_SET: break;
      }
      return d;
    }
    case scenario::Disturbance::kTransientBurst: {
      const scenario::TransientBurst& p = proto.transient_burst();
      const std::string p_path = path + ".transient_burst";
      d.kind = DisturbanceConfig::Kind::kTransientBurst;
      d.start_s = p.start_s();
      d.duration_s = p.duration_s();
      if (p.has_rate_rad_per_s()) d.rate_rad_per_s = p.rate_rad_per_s();
      d.period_s = p.period_s();
      switch (p.envelope()) {
        case scenario::ENVELOPE_UNSPECIFIED:
        case scenario::HALF_SINE: d.envelope = DisturbanceConfig::Envelope::kHalfSine; break;
        case scenario::RECTANGULAR: d.envelope = DisturbanceConfig::Envelope::kRectangular; break;
        default: FailEnum(p_path + ".envelope", p.envelope(), scenario::Envelope_descriptor());
      }
      switch (p.axis_kind_case()) {
        case scenario::TransientBurst::kAxis:
          d.axis = AxisFromEnum(p.axis(), d.axis, p_path + ".axis");
          break;
        case scenario::TransientBurst::kAxisVector:
          d.axis = VectorFromProto(p.axis_vector());
          break;
        case scenario::TransientBurst::kRandomAxis: d.random_axis = p.random_axis(); break;
        case scenario::TransientBurst::AXIS_KIND_NOT_SET: break;
      }
      return d;
    }
    case scenario::Disturbance::KIND_NOT_SET: break;
  }
  throw ScenarioError(path, "the disturbance has no kind; set one of paper_scrambler, "
                            "random_walk, constant_rotation, transient_burst");
}

ControlMethod MethodFromProto(scenario::Method method) {
  switch (method) {
    case scenario::METHOD_UNSPECIFIED:
    case scenario::GP: return ControlMethod::kGradientProjection;
    case scenario::INVERSE: return ControlMethod::kInverse;
    case scenario::TRANSPOSE: return ControlMethod::kTranspose;
    case scenario::DAMPED: return ControlMethod::kDamped;
    case scenario::PINV: return ControlMethod::kPseudoInverse;
    case scenario::RLS: return ControlMethod::kRegularizedLeastSquares;
    case scenario::GPT: return ControlMethod::kThresholdedGradientProjection;
    case scenario::EXTENDED: return ControlMethod::kExtendedJacobian;
    case scenario::DITHER: return ControlMethod::kDither;
    default: FailEnum("controller.method", method, scenario::Method_descriptor());
  }
}

ControllerConfig ControllerFromProto(const scenario::Controller& p) {
  ControllerConfig c;
  c.method = MethodFromProto(p.method());
  if (p.has_step()) c.step = p.step();
  if (p.has_nullspace_step()) c.nullspace_step = p.nullspace_step();
  if (p.has_threshold()) c.threshold = p.threshold();
  if (p.has_damping()) c.damping = p.damping();
  if (p.has_singular_value_tolerance()) c.singular_value_tolerance = p.singular_value_tolerance();
  switch (p.loop()) {
    case scenario::LOOP_MODE_UNSPECIFIED:
    case scenario::MODEL: c.loop = LoopMode::kModel; break;
    case scenario::MEASURED: c.loop = LoopMode::kMeasured; break;
    default: FailEnum("controller.loop", p.loop(), scenario::LoopMode_descriptor());
  }
  if (p.has_activation_s()) c.activation_s = p.activation_s();
  c.initial_phi.assign(p.initial_phi().begin(), p.initial_phi().end());
  const scenario::Dither& dither = p.dither();
  if (dither.has_amplitude()) c.dither.amplitude = dither.amplitude();
  if (dither.has_settle_samples()) c.dither.settle_samples = dither.settle_samples();
  if (dither.has_reset_threshold()) c.dither.reset_threshold = dither.reset_threshold();
  if (dither.has_reset_duration_s()) c.dither.reset_duration_s = dither.reset_duration_s();
  if (p.has_singularity_damping()) {
    SingularityDampingConfig damping;
    const scenario::SingularityDamping& d = p.singularity_damping();
    if (d.has_max_damping()) damping.max_damping = d.max_damping();
    if (d.has_threshold()) damping.threshold = d.threshold();
    c.singularity_damping = damping;
  }
  switch (p.nullspace_criterion()) {
    case scenario::NULLSPACE_CRITERION_UNSPECIFIED:
    case scenario::MIN_NORM: c.nullspace_criterion = NullspaceCriterion::kMinimumNorm; break;
    case scenario::RANGE: c.nullspace_criterion = NullspaceCriterion::kRange; break;
    default:
      FailEnum("controller.nullspace_criterion", p.nullspace_criterion(),
               scenario::NullspaceCriterion_descriptor());
  }
  if (p.has_prediction()) {
    PredictionConfig prediction;
    const scenario::Prediction& q = p.prediction();
    if (q.has_window_samples()) prediction.window_samples = q.window_samples();
    if (q.has_horizon_samples()) prediction.horizon_samples = q.horizon_samples();
    if (q.has_lead_samples()) prediction.lead_samples = q.lead_samples();
    c.prediction = prediction;
  }
  c.curvature_correction = p.curvature_correction();
  return c;
}

SimulationConfig SimulationFromProto(const scenario::Simulation& p) {
  SimulationConfig s;
  if (p.has_sample_rate_hz()) s.sample_rate_hz = p.sample_rate_hz();
  if (p.has_delay_s()) s.delay_s = p.delay_s();
  if (p.has_duration_s()) s.duration_s = p.duration_s();
  if (p.has_polarimeter_noise_deg()) s.polarimeter_noise_deg = p.polarimeter_noise_deg();
  if (p.has_seed()) s.seed = p.seed();
  if (p.has_lock_threshold_deg()) s.lock_threshold_deg = p.lock_threshold_deg();
  if (p.has_statistics_start_s()) s.statistics_start_s = p.statistics_start_s();
  if (p.has_settle_samples()) s.settle_samples = p.settle_samples();
  return s;
}

InstrumentLinkConfig LinkFromProto(const scenario::InstrumentLink& p) {
  InstrumentLinkConfig link;
  switch (p.kind_case()) {
    case scenario::InstrumentLink::kTcp:
      link.kind = InstrumentLinkConfig::Kind::kTcp;
      if (!p.tcp().host().empty()) link.host = p.tcp().host();
      link.port = static_cast<int>(std::min<uint32_t>(p.tcp().port(), 1u << 30));
      break;
    case scenario::InstrumentLink::kSerial:
      link.kind = InstrumentLinkConfig::Kind::kSerial;
      link.path = p.serial().path();
      if (p.serial().has_baud()) link.baud = static_cast<int>(std::min<uint32_t>(p.serial().baud(), 1u << 30));
      break;
    case scenario::InstrumentLink::KIND_NOT_SET:
      link.port = 0;  // validation names the missing link
      break;
  }
  if (p.has_response_timeout_s()) link.response_timeout_s = p.response_timeout_s();
  if (p.has_reconnect_min_s()) link.reconnect_min_s = p.reconnect_min_s();
  if (p.has_reconnect_max_s()) link.reconnect_max_s = p.reconnect_max_s();
  return link;
}

WaveplateDeviceConfig WaveplateDeviceFromProto(const scenario::WaveplateDevice& p) {
  WaveplateDeviceConfig d;
  d.link = LinkFromProto(p.link());
  if (p.has_set_command()) d.set_command = p.set_command();
  for (const uint32_t channel : p.channels()) d.channels.push_back(static_cast<int>(std::min<uint32_t>(channel, 1u << 30)));
  if (p.has_ack()) d.ack = p.ack();
  if (p.has_identify()) d.identify = p.identify();
  if (p.has_volts_min()) d.volts_min = p.volts_min();
  if (p.has_volts_max()) d.volts_max = p.volts_max();
  if (p.has_dac_bits()) d.dac_bits = static_cast<int>(std::min<uint32_t>(p.dac_bits(), 1u << 30));
  if (p.has_max_slew_v_per_s()) d.max_slew_v_per_s = p.max_slew_v_per_s();
  if (p.has_read_command()) d.read_command = p.read_command();
  d.settling_s = p.settling_s();
  return d;
}

PolarimeterDeviceConfig PolarimeterDeviceFromProto(const scenario::PolarimeterDevice& p) {
  PolarimeterDeviceConfig d;
  d.link = LinkFromProto(p.link());
  if (p.has_query()) d.query = p.query();
  switch (p.reply()) {
    case scenario::PolarimeterDevice::S_IN: d.reply = PolarimeterDeviceConfig::Reply::kInput; break;
    case scenario::PolarimeterDevice::S_IN_AND_S_OUT: d.reply = PolarimeterDeviceConfig::Reply::kInputAndOutput; break;
    default: d.reply = PolarimeterDeviceConfig::Reply::kOutput; break;
  }
  if (p.has_min_dop()) d.min_dop = p.min_dop();
  d.reports_power = p.reports_power();
  d.stream = p.stream();
  d.stream_start = p.stream_start();
  return d;
}

}  // namespace

scenario::Scenario ParseScenarioText(std::string_view text, const std::string& source_name) {
  if (text.size() > kMaxScenarioTextBytes) {
    throw ScenarioError(source_name,
                        fmt::format("the scenario text has {} bytes; at most {} (16 MiB)",
                                    text.size(), kMaxScenarioTextBytes));
  }
  FirstErrorCollector errors;
  pb::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  pb::io::ArrayInputStream input(text.data(), static_cast<int>(text.size()));
  scenario::Scenario proto;
  if (!parser.Parse(&input, &proto)) {
    if (!errors.error()) throw ScenarioError(source_name, "not a valid scenario text");
    const auto& error = *errors.error();
    const std::string location =
        error.line < 0 ? source_name
                       : fmt::format("{}:{}:{}", source_name, error.line + 1, error.column + 1);
    throw ScenarioError(location, error.message);
  }
  return proto;
}

ScenarioConfig ScenarioFromProto(const scenario::Scenario& proto) {
  ScenarioConfig config;
  if (!proto.name().empty()) config.name = proto.name();
  config.description = proto.description();
  for (int i = 0; i < proto.stages_size(); ++i) {
    config.stages.push_back(StageFromProto(proto.stages(i), fmt::format("stages[{}]", i)));
  }
  if (proto.input().has_initial_sop()) {
    config.input.initial_sop = VectorFromProto(proto.input().initial_sop());
  }
  for (int k = 0; k < proto.input().disturbances_size(); ++k) {
    config.input.disturbances.push_back(DisturbanceFromProto(
        proto.input().disturbances(k), fmt::format("input.disturbances[{}]", k)));
  }
  const scenario::Target& target = proto.target();
  switch (target.kind_case()) {
    case scenario::Target::kPoint:
      config.target.kind = TargetConfig::Kind::kPoint;
      config.target.point = VectorFromProto(target.point());
      break;
    case scenario::Target::kSet:
      config.target.kind = TargetConfig::Kind::kSet;
      if (target.set().has_normal()) config.target.normal = VectorFromProto(target.set().normal());
      config.target.offset = target.set().offset();
      break;
    case scenario::Target::KIND_NOT_SET: break;  // the default point [0, 0.6, 0.8]
  }
  config.controller = ControllerFromProto(proto.controller());
  config.simulation = SimulationFromProto(proto.simulation());
  if (proto.has_waveplate_device()) config.waveplate_device = WaveplateDeviceFromProto(proto.waveplate_device());
  if (proto.has_polarimeter_device()) config.polarimeter_device = PolarimeterDeviceFromProto(proto.polarimeter_device());
  return config;
}

}  // namespace dpc
