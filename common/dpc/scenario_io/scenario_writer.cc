#include "dpc/scenario_io/scenario_writer.h"

#include <google/protobuf/text_format.h>

#include <algorithm>
#include <optional>

namespace dpc {
namespace {

namespace pb = google::protobuf;

// ---------------------------------------------------------------------------------------------
// Config → proto.

void VectorToProto(const Vector3& v, scenario::Vector3* proto) {
  proto->set_s1(v.x());
  proto->set_s2(v.y());
  proto->set_s3(v.z());
}

/// S1, S2 or S3 if `v` is exactly that unit vector.
std::optional<scenario::Axis> ElementalAxis(const Vector3& v) {
  if (v == Vector3::UnitX()) return scenario::S1;
  if (v == Vector3::UnitY()) return scenario::S2;
  if (v == Vector3::UnitZ()) return scenario::S3;
  return std::nullopt;
}

void MapToProto(const ControlMapConfig& map, scenario::ControlMap* proto) {
  switch (map.kind) {
    case ControlMapConfig::Kind::kLinear:
      proto->mutable_linear()->set_rad_per_unit(map.rad_per_unit);
      proto->mutable_linear()->set_offset_rad(map.offset_rad);
      return;
    case ControlMapConfig::Kind::kPolynomial: {
      auto* coefficients = proto->mutable_polynomial()->mutable_coefficients_rad();
      coefficients->Add(map.coefficients_rad.begin(), map.coefficients_rad.end());
      return;
    }
    case ControlMapConfig::Kind::kTable: {
      auto* table = proto->mutable_table();
      table->mutable_control()->Add(map.table_control.begin(), map.table_control.end());
      table->mutable_angle_rad()->Add(map.table_angle_rad.begin(), map.table_angle_rad.end());
      return;
    }
    case ControlMapConfig::Kind::kTablesByCondition: {
      const bool by_temperature = map.condition == ControlMapConfig::Condition::kTemperatureC;
      scenario::TablesByCondition* keyed = proto->mutable_tables_by_condition();
      if (by_temperature) {
        keyed->set_operating_temperature_c(map.operating_point);
      } else {
        keyed->set_operating_wavelength_nm(map.operating_point);
      }
      for (const ConditionTableConfig& condition_table : map.condition_tables) {
        scenario::TableAtCondition* at = keyed->add_tables();
        if (by_temperature) {
          at->set_temperature_c(condition_table.condition);
        } else {
          at->set_wavelength_nm(condition_table.condition);
        }
        at->mutable_table()->mutable_control()->Add(condition_table.control.begin(), condition_table.control.end());
        at->mutable_table()->mutable_angle_rad()->Add(condition_table.angle_rad.begin(),
                                                      condition_table.angle_rad.end());
      }
      return;
    }
  }
}

void RangeToProto(const ControlRange& range, scenario::ControlRange* proto) {
  proto->set_min(range.min);
  proto->set_max(range.max);
}

void AngleToProto(const StageAngleConfig& angle, scenario::StageAngle* proto) {
  if (!angle.controlled) {
    proto->set_fixed_rad(angle.fixed_rad);
    return;
  }
  scenario::ControlledAngle* controlled = proto->mutable_controlled();
  MapToProto(angle.map, controlled->mutable_map());
  if (angle.range) RangeToProto(*angle.range, controlled->mutable_range());
}

void StageToProto(const StageConfig& stage, scenario::Stage* proto) {
  proto->set_name(stage.name);
  if (stage.kind == StageConfig::Kind::kAdjustableAxis) {
    AngleToProto(stage.retardance, proto->mutable_adjustable_axis()->mutable_retardance());
    AngleToProto(stage.orientation, proto->mutable_adjustable_axis()->mutable_orientation());
    return;
  }
  if (const auto axis = ElementalAxis(stage.axis)) {
    proto->set_axis(*axis);
  } else {
    VectorToProto(stage.axis, proto->mutable_axis_vector());
  }
  MapToProto(stage.map, proto->mutable_map());
  if (stage.range) RangeToProto(*stage.range, proto->mutable_range());
}

void DisturbanceToProto(const DisturbanceConfig& d, scenario::Disturbance* proto) {
  switch (d.kind) {
    case DisturbanceConfig::Kind::kPaperScrambler: {
      scenario::PaperScrambler* p = proto->mutable_paper_scrambler();
      p->set_rate_rad_per_s(d.rate_rad_per_s);
      p->set_kick_rms_ratio(d.kick_rms_ratio);
      if (const auto axis = ElementalAxis(d.axis)) {
        p->set_rotation_axis(*axis);
      } else {
        VectorToProto(d.axis, p->mutable_rotation_axis_vector());
      }
      if (const auto axis = ElementalAxis(d.kick_axis)) {
        p->set_kick_axis(*axis);
      } else {
        VectorToProto(d.kick_axis, p->mutable_kick_axis_vector());
      }
      return;
    }
    case DisturbanceConfig::Kind::kRandomWalk:
      proto->mutable_random_walk()->set_diffusion_rad_per_sqrt_s(d.diffusion_rad_per_sqrt_s);
      return;
    case DisturbanceConfig::Kind::kConstantRotation: {
      scenario::ConstantRotation* p = proto->mutable_constant_rotation();
      p->set_rate_rad_per_s(d.rate_rad_per_s);
      if (const auto axis = ElementalAxis(d.axis)) {
        p->set_axis(*axis);
      } else {
        VectorToProto(d.axis, p->mutable_axis_vector());
      }
      return;
    }
    case DisturbanceConfig::Kind::kTransientBurst: {
      scenario::TransientBurst* p = proto->mutable_transient_burst();
      p->set_start_s(d.start_s);
      p->set_duration_s(d.duration_s);
      p->set_rate_rad_per_s(d.rate_rad_per_s);
      p->set_period_s(d.period_s);
      p->set_envelope(d.envelope == DisturbanceConfig::Envelope::kRectangular
                          ? scenario::RECTANGULAR
                          : scenario::HALF_SINE);
      if (d.random_axis) {
        p->set_random_axis(true);
      } else if (const auto axis = ElementalAxis(d.axis)) {
        p->set_axis(*axis);
      } else {
        VectorToProto(d.axis, p->mutable_axis_vector());
      }
      return;
    }
  }
}

scenario::Method MethodToProto(ControlMethod method) {
  switch (method) {
    case ControlMethod::kInverse: return scenario::INVERSE;
    case ControlMethod::kTranspose: return scenario::TRANSPOSE;
    case ControlMethod::kDamped: return scenario::DAMPED;
    case ControlMethod::kPseudoInverse: return scenario::PINV;
    case ControlMethod::kRegularizedLeastSquares: return scenario::RLS;
    case ControlMethod::kGradientProjection: return scenario::GP;
    case ControlMethod::kThresholdedGradientProjection: return scenario::GPT;
    case ControlMethod::kExtendedJacobian: return scenario::EXTENDED;
    case ControlMethod::kDither: return scenario::DITHER;
  }
  return scenario::METHOD_UNSPECIFIED;
}

void ControllerToProto(const ControllerConfig& c, scenario::Controller* p) {
  p->set_method(MethodToProto(c.method));
  p->set_step(c.step);
  p->set_nullspace_step(c.nullspace_step);
  p->set_threshold(c.threshold);
  p->set_damping(c.damping);
  p->set_singular_value_tolerance(c.singular_value_tolerance);
  p->set_loop(c.loop == LoopMode::kMeasured ? scenario::MEASURED : scenario::MODEL);
  p->set_activation_s(c.activation_s);
  p->mutable_initial_phi()->Add(c.initial_phi.begin(), c.initial_phi.end());
  scenario::Dither* dither = p->mutable_dither();
  dither->set_amplitude(c.dither.amplitude);
  dither->set_settle_samples(c.dither.settle_samples);
  dither->set_reset_threshold(c.dither.reset_threshold);
  dither->set_reset_duration_s(c.dither.reset_duration_s);
  if (c.singularity_damping) {
    scenario::SingularityDamping* d = p->mutable_singularity_damping();
    d->set_max_damping(c.singularity_damping->max_damping);
    d->set_threshold(c.singularity_damping->threshold);
  }
  p->set_nullspace_criterion(c.nullspace_criterion == NullspaceCriterion::kRange
                                 ? scenario::RANGE
                                 : scenario::MIN_NORM);
  if (c.prediction) {
    scenario::Prediction* q = p->mutable_prediction();
    q->set_window_samples(c.prediction->window_samples);
    if (c.prediction->horizon_samples) q->set_horizon_samples(*c.prediction->horizon_samples);
    if (c.prediction->lead_samples) q->set_lead_samples(*c.prediction->lead_samples);
  }
  p->set_curvature_correction(c.curvature_correction);
}

void SimulationToProto(const SimulationConfig& s, scenario::Simulation* p) {
  p->set_sample_rate_hz(s.sample_rate_hz);
  p->set_delay_s(s.delay_s);
  p->set_duration_s(s.duration_s);
  p->set_polarimeter_noise_deg(s.polarimeter_noise_deg);
  p->set_seed(s.seed);
  p->set_lock_threshold_deg(s.lock_threshold_deg);
  if (s.statistics_start_s) p->set_statistics_start_s(*s.statistics_start_s);
  p->set_settle_samples(s.settle_samples);
}

void LinkToProto(const InstrumentLinkConfig& link, scenario::InstrumentLink* p) {
  if (link.kind == InstrumentLinkConfig::Kind::kTcp) {
    p->mutable_tcp()->set_host(link.host);
    p->mutable_tcp()->set_port(static_cast<uint32_t>(std::max(link.port, 0)));
  } else {
    p->mutable_serial()->set_path(link.path);
    p->mutable_serial()->set_baud(static_cast<uint32_t>(std::max(link.baud, 0)));
  }
  p->set_response_timeout_s(link.response_timeout_s);
  p->set_reconnect_min_s(link.reconnect_min_s);
  p->set_reconnect_max_s(link.reconnect_max_s);
}

void WaveplateDeviceToProto(const WaveplateDeviceConfig& d, scenario::WaveplateDevice* p) {
  LinkToProto(d.link, p->mutable_link());
  p->set_set_command(d.set_command);
  for (const int channel : d.channels) p->add_channels(static_cast<uint32_t>(std::max(channel, 0)));
  p->set_ack(d.ack);
  p->set_identify(d.identify);
  p->set_volts_min(d.volts_min);
  p->set_volts_max(d.volts_max);
  p->set_dac_bits(static_cast<uint32_t>(std::max(d.dac_bits, 0)));
  p->set_max_slew_v_per_s(d.max_slew_v_per_s);
  p->set_read_command(d.read_command);
  p->set_settling_s(d.settling_s);
}

void PolarimeterDeviceToProto(const PolarimeterDeviceConfig& d, scenario::PolarimeterDevice* p) {
  LinkToProto(d.link, p->mutable_link());
  p->set_query(d.query);
  switch (d.reply) {
    case PolarimeterDeviceConfig::Reply::kOutput: p->set_reply(scenario::PolarimeterDevice::S_OUT); break;
    case PolarimeterDeviceConfig::Reply::kInput: p->set_reply(scenario::PolarimeterDevice::S_IN); break;
    case PolarimeterDeviceConfig::Reply::kInputAndOutput:
      p->set_reply(scenario::PolarimeterDevice::S_IN_AND_S_OUT);
      break;
  }
  p->set_min_dop(d.min_dop);
  p->set_reports_power(d.reports_power);
  p->set_stream(d.stream);
  if (!d.stream_start.empty()) p->set_stream_start(d.stream_start);
}

}  // namespace

scenario::Scenario ScenarioToProto(const ScenarioConfig& config) {
  scenario::Scenario proto;
  proto.set_name(config.name);
  proto.set_description(config.description);
  for (const StageConfig& stage : config.stages) StageToProto(stage, proto.add_stages());
  VectorToProto(config.input.initial_sop, proto.mutable_input()->mutable_initial_sop());
  for (const DisturbanceConfig& d : config.input.disturbances) {
    DisturbanceToProto(d, proto.mutable_input()->add_disturbances());
  }
  if (config.target.kind == TargetConfig::Kind::kPoint) {
    VectorToProto(config.target.point, proto.mutable_target()->mutable_point());
  } else {
    scenario::LinearSet* set = proto.mutable_target()->mutable_set();
    VectorToProto(config.target.normal, set->mutable_normal());
    set->set_offset(config.target.offset);
  }
  ControllerToProto(config.controller, proto.mutable_controller());
  SimulationToProto(config.simulation, proto.mutable_simulation());
  if (config.waveplate_device) WaveplateDeviceToProto(*config.waveplate_device, proto.mutable_waveplate_device());
  if (config.polarimeter_device) {
    PolarimeterDeviceToProto(*config.polarimeter_device, proto.mutable_polarimeter_device());
  }
  return proto;
}

std::string ScenarioToText(const ScenarioConfig& config) {
  std::string text;
  if (!pb::TextFormat::PrintToString(ScenarioToProto(config), &text)) {
    throw ScenarioError(config.name, "cannot print the scenario as text");
  }
  return text;
}

}  // namespace dpc
