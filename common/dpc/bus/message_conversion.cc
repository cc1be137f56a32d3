#include "dpc/bus/message_conversion.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::bus {
namespace {

msg::ControlMap MapMessage(const ControlMapConfig& configured) {
  // Tables by condition travel as the table they stand for at the operating point.
  const ControlMapConfig map = ResolveConditionTables(configured);
  msg::ControlMap out;
  switch (map.kind) {
    case ControlMapConfig::Kind::kLinear: out.kind(msg::MAP_LINEAR); break;
    case ControlMapConfig::Kind::kPolynomial: out.kind(msg::MAP_POLYNOMIAL); break;
    case ControlMapConfig::Kind::kTable:
    case ControlMapConfig::Kind::kTablesByCondition: out.kind(msg::MAP_TABLE); break;
  }
  out.rad_per_unit(map.rad_per_unit);
  out.offset_rad(map.offset_rad);
  out.coefficients_rad(map.coefficients_rad);
  out.table_control(map.table_control);
  out.table_angle_rad(map.table_angle_rad);
  return out;
}

ControlMapConfig MapConfig(const msg::ControlMap& map, const std::string& path) {
  ControlMapConfig out;
  switch (map.kind()) {
    case msg::MAP_LINEAR: out.kind = ControlMapConfig::Kind::kLinear; break;
    case msg::MAP_POLYNOMIAL: out.kind = ControlMapConfig::Kind::kPolynomial; break;
    case msg::MAP_TABLE: out.kind = ControlMapConfig::Kind::kTable; break;
    default:
      throw std::invalid_argument(fmt::format("{}.kind: unknown control map kind {}", path,
                                              static_cast<int>(map.kind())));
  }
  for (const auto* values : {&map.coefficients_rad(), &map.table_control(), &map.table_angle_rad()}) {
    if (values->size() > msg::MAX_MAP_POINTS) {
      throw std::invalid_argument(fmt::format("{}: {} points, more than the {} a control map may have (oversized)",
                                              path, values->size(), msg::MAX_MAP_POINTS));
    }
  }
  out.rad_per_unit = map.rad_per_unit();
  out.offset_rad = map.offset_rad();
  // Only what the kind uses: nothing a check skipped is kept.
  if (out.kind == ControlMapConfig::Kind::kPolynomial) out.coefficients_rad = map.coefficients_rad();
  if (out.kind == ControlMapConfig::Kind::kTable) {
    out.table_control = map.table_control();
    out.table_angle_rad = map.table_angle_rad();
  }
  return out;
}

msg::ControlRange RangeMessage(const std::optional<ControlRange>& range) {
  msg::ControlRange out;
  out.limited(range.has_value());
  out.min_phi(range ? range->min : 0.0);
  out.max_phi(range ? range->max : 0.0);
  return out;
}

std::optional<ControlRange> RangeConfig(const msg::ControlRange& range) {
  if (!range.limited()) return std::nullopt;
  return ControlRange{range.min_phi(), range.max_phi()};
}

msg::StageAngle AngleMessage(const StageAngleConfig& angle) {
  msg::StageAngle out;
  out.controlled(angle.controlled);
  out.fixed_rad(angle.fixed_rad);
  out.control_map(MapMessage(angle.map));
  out.range(RangeMessage(angle.range));
  return out;
}

StageAngleConfig AngleConfig(const msg::StageAngle& angle, const std::string& path) {
  StageAngleConfig out;
  out.controlled = angle.controlled();
  out.fixed_rad = angle.fixed_rad();
  out.map = MapConfig(angle.control_map(), path + ".map");
  out.range = RangeConfig(angle.range());
  return out;
}

template <typename Array>
bool AllFinite(const Array& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}


/// Empty if every value is finite; else the first that is not, as "field[i] = v is not finite".
std::string CheckFinite(const std::vector<double>& values, const char* field) {
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) return fmt::format("{}[{}] = {} is not finite", field, i, values[i]);
  }
  return {};
}

/// Empty if `rates` (phi_rate_per_s of a command or a state) is empty (φ holds) or has one
/// finite value per control.
std::string CheckRates(const std::vector<double>& rates, size_t controls) {
  if (!rates.empty() && rates.size() != controls) {
    return fmt::format("phi_rate_per_s has {} values, the device has {} controls (or none: φ holds)",
                       rates.size(), controls);
  }
  return CheckFinite(rates, "phi_rate_per_s");
}

}  // namespace

std::string CheckUnitStokes(const std::array<double, 3>& s, const char* field) {
  if (!AllFinite(s)) {
    return fmt::format("{} = [{}, {}, {}] is not finite", field, s[0], s[1], s[2]);
  }
  const double norm = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (!(std::abs(norm - 1.0) <= kUnitStokesTolerance)) {
    return fmt::format("{} = [{}, {}, {}] is not a unit Stokes vector (|S| = {:.9g})", field,
                       s[0], s[1], s[2], norm);
  }
  return {};
}

std::string ReadSample(const msg::StokesSample& message, BenchSample* out) {
  if (message.sequence_number() == 0) return "sequence_number 0 (sequences start at 1)";
  if (std::string reason = CheckUnitStokes(message.s_in(), "s_in"); !reason.empty()) return reason;
  if (std::string reason = CheckUnitStokes(message.s_out(), "s_out"); !reason.empty()) return reason;
  if (message.optical_power_known() &&
      !(std::isfinite(message.optical_power_w()) && message.optical_power_w() >= 0.0)) {
    return fmt::format("optical_power_w = {} is not a finite power >= 0", message.optical_power_w());
  }
  out->sequence = message.sequence_number();
  out->time_ns = message.sample_time_ns();
  out->publish_time_ns = message.publish_time_ns();
  out->s_in = ToStokes(message.s_in());
  out->s_out = ToStokes(message.s_out());
  out->optical_power_w = message.optical_power_known() ? std::optional<double>(message.optical_power_w())
                                                       : std::nullopt;
  out->lockstep = message.lockstep();
  return {};
}

void WriteSample(const BenchSample& sample, const std::string& bench_id, msg::StokesSample* out) {
  out->bench_id(bench_id);
  out->sequence_number(sample.sequence);
  out->sample_time_ns(sample.time_ns);
  out->publish_time_ns(sample.publish_time_ns);
  out->s_in(ToArray(sample.s_in));
  out->s_out(ToArray(sample.s_out));
  out->optical_power_known(sample.optical_power_w.has_value());
  out->optical_power_w(sample.optical_power_w.value_or(0.0));
  out->lockstep(sample.lockstep);
}

namespace {

/// `values` (one per control, already checked) into `out` without allocating.
void ReadControls(const std::vector<double>& values, ControlVector* out) {
  out->resize(static_cast<Eigen::Index>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) (*out)[static_cast<Eigen::Index>(i)] = values[i];
}

void WriteControls(const ControlVector& values, std::vector<double>* out) {
  out->assign(values.data(), values.data() + values.size());
}

}  // namespace

std::string ReadCommand(const msg::WaveplateCommand& message, int control_count, ControllerCommand* out) {
  out->controller_id.assign(message.controller_id().c_str(), message.controller_id().size());
  out->answers_sample = message.answers_sample();
  const size_t count = message.phi().size();
  if (message.controller_id().size() == 0) return "empty controller_id";
  if (count > msg::MAX_CONTROLS) {
    return fmt::format("phi has {} values, more than the {} any device may have (oversized)",
                       count, msg::MAX_CONTROLS);
  }
  if (count != static_cast<size_t>(control_count)) {
    return fmt::format("phi has {} values, the device has {} controls", count, control_count);
  }
  if (std::string reason = CheckFinite(message.phi(), "phi"); !reason.empty()) return reason;
  if (std::string reason = CheckRates(message.phi_rate_per_s(), count); !reason.empty()) return reason;
  out->priority = message.priority();
  out->sequence = message.sequence_number();
  out->sample_time_ns = message.sample_time_ns();
  out->sample_publish_time_ns = message.sample_publish_time_ns();
  out->publish_time_ns = message.publish_time_ns();
  ReadControls(message.phi(), &out->phi);
  ReadControls(message.phi_rate_per_s(), &out->rate_per_s);
  return {};
}

void WriteCommand(const ControllerCommand& command, const std::string& bench_id, msg::WaveplateCommand* out) {
  out->bench_id(bench_id);
  out->controller_id(command.controller_id);
  out->priority(command.priority);
  out->sequence_number(command.sequence);
  out->answers_sample(command.answers_sample);
  out->sample_time_ns(command.sample_time_ns);
  out->sample_publish_time_ns(command.sample_publish_time_ns);
  out->publish_time_ns(command.publish_time_ns);
  WriteControls(command.phi, &out->phi());
  WriteControls(command.rate_per_s, &out->phi_rate_per_s());
}

std::string ReadState(const msg::WaveplateState& message, int control_count, DriverState* out) {
  const size_t controls = static_cast<size_t>(control_count);
  if (message.phi_applied().size() > msg::MAX_CONTROLS) {
    return fmt::format("phi_applied has {} values, more than the {} any device may have (oversized)",
                       message.phi_applied().size(), msg::MAX_CONTROLS);
  }
  if (message.phi_applied().size() != controls) {
    return fmt::format("phi_applied has {} values, the device has {} controls",
                       message.phi_applied().size(), controls);
  }
  if (std::string reason = CheckFinite(message.phi_applied(), "phi_applied"); !reason.empty()) return reason;
  if (std::string reason = CheckRates(message.phi_rate_per_s(), controls); !reason.empty()) return reason;
  if (message.mode() != msg::DRIVER_ACTIVE && message.mode() != msg::DRIVER_HOLDING) {
    return fmt::format("mode {} is not a driver mode", static_cast<int>(message.mode()));
  }
  if (!message.saturated().empty() && message.saturated().size() != controls) {
    return fmt::format("saturated has {} values, the device has {} controls", message.saturated().size(),
                       controls);
  }
  const bool rated = !message.phi_rate_per_s().empty();
  if (rated) {
    if (message.ramp_end_time_ns() < message.ramp_start_time_ns()) {
      return fmt::format("ramp_end_time_ns {} is before ramp_start_time_ns {}", message.ramp_end_time_ns(),
                         message.ramp_start_time_ns());
    }
    // Overflow-safe: the difference of two arbitrary int64 does not fit an int64.
    const uint64_t ramp_ns = static_cast<uint64_t>(message.ramp_end_time_ns()) -
                             static_cast<uint64_t>(message.ramp_start_time_ns());
    if (ramp_ns > kMaxStateRampNs) {
      return fmt::format("the ramp lasts {} ns, longer than any driver ramps ({} ns)", ramp_ns,
                         kMaxStateRampNs);
    }
  }
  out->sequence = message.sequence_number();
  out->answers_sample = message.answers_sample();
  out->sample_time_ns = message.sample_time_ns();
  out->sample_publish_time_ns = message.sample_publish_time_ns();
  out->command_receive_time_ns = message.command_receive_time_ns();
  out->publish_time_ns = message.publish_time_ns();
  WaveplateMotion& motion = out->motion;
  ReadControls(message.phi_applied(), &motion.phi);
  motion.rate_per_s.resize(control_count);
  bool moving = false;
  for (size_t i = 0; i < controls; ++i) {
    const double rate = rated ? message.phi_rate_per_s()[i] : 0.0;
    motion.rate_per_s[static_cast<Eigen::Index>(i)] = rate;
    moving = moving || rate != 0.0;
  }
  motion.start_ns = message.ramp_start_time_ns();
  motion.end_ns = rated ? message.ramp_end_time_ns() : message.ramp_start_time_ns();
  motion.moving = moving && motion.end_ns > motion.start_ns;
  if (motion.moving) {
    // Each value finite is not enough: φ + φ̇·T must be too (1e308 + 1e308·1 s is not).
    ControlVector end(control_count);
    motion.At(motion.end_ns, &end);
    for (Eigen::Index i = 0; i < end.size(); ++i) {
      if (!std::isfinite(end[i])) {
        return fmt::format("the motion of control {} does not stay finite over its ramp", i);
      }
    }
  }
  out->saturated.fill(false);
  for (size_t i = 0; i < message.saturated().size(); ++i) out->saturated[i] = message.saturated()[i];
  out->mode = message.mode() == msg::DRIVER_ACTIVE ? DriverMode::kActive : DriverMode::kHolding;
  out->reason.assign(message.reason().c_str(), message.reason().size());
  out->obeyed_controller_id.assign(message.obeyed_controller_id().c_str(),
                                   message.obeyed_controller_id().size());
  out->obeyed_priority = message.obeyed_priority();
  out->commands_applied = message.commands_applied();
  out->commands_rejected = message.commands_rejected();
  out->commands_limited = message.commands_limited();
  out->controller_switches = message.controller_switches();
  out->last_rejection.assign(message.last_rejection().c_str(), message.last_rejection().size());
  out->applied_controller_id.assign(message.applied_controller_id().c_str(), message.applied_controller_id().size());
  out->stand_ins = message.stand_ins();
  return {};
}

void WriteState(const DriverState& state, const std::string& bench_id, msg::WaveplateState* out) {
  out->bench_id(bench_id);
  out->sequence_number(state.sequence);
  out->answers_sample(state.answers_sample);
  out->sample_time_ns(state.sample_time_ns);
  out->sample_publish_time_ns(state.sample_publish_time_ns);
  out->command_receive_time_ns(state.command_receive_time_ns);
  out->publish_time_ns(state.publish_time_ns);
  const WaveplateMotion& motion = state.motion;
  WriteControls(motion.phi, &out->phi_applied());
  if (motion.moving) {
    WriteControls(motion.rate_per_s, &out->phi_rate_per_s());
  } else {
    out->phi_rate_per_s().clear();
  }
  out->ramp_start_time_ns(motion.start_ns);
  out->ramp_end_time_ns(motion.moving ? motion.end_ns : motion.start_ns);
  out->saturated().assign(state.saturated.begin(), state.saturated.begin() + state.control_count());
  out->mode(state.mode == DriverMode::kActive ? msg::DRIVER_ACTIVE : msg::DRIVER_HOLDING);
  out->reason(state.reason.substr(0, 255));
  out->obeyed_controller_id(state.obeyed_controller_id.substr(0, 63));
  out->obeyed_priority(state.obeyed_priority);
  out->commands_applied(state.commands_applied);
  out->commands_rejected(state.commands_rejected);
  out->commands_limited(state.commands_limited);
  out->controller_switches(state.controller_switches);
  out->last_rejection(state.last_rejection.substr(0, 255));
  out->applied_controller_id(state.applied_controller_id.substr(0, 63));
  out->stand_ins(state.stand_ins);
}

msg::DeviceDescription DeviceMessage(const DeviceDescription& device, const std::string& bench_id) {
  msg::DeviceDescription out;
  out.bench_id(bench_id);
  out.driver_id(device.driver_id);
  out.max_slew_per_s(device.max_slew_per_s);
  out.max_ramp_s(device.max_ramp_s);
  for (const StageConfig& stage : device.stages) {
    msg::Stage s;
    s.kind(stage.kind == StageConfig::Kind::kFixedAxis ? msg::STAGE_FIXED_AXIS
                                                      : msg::STAGE_ADJUSTABLE_AXIS);
    s.name(stage.name);
    s.axis(ToArray(stage.axis));
    s.control_map(MapMessage(stage.map));
    s.range(RangeMessage(stage.range));
    s.retardance(AngleMessage(stage.retardance));
    s.orientation(AngleMessage(stage.orientation));
    out.stages().push_back(s);
  }
  return out;
}

std::string ReadDevice(const msg::DeviceDescription& message, DeviceDescription* out) {
  try {
    std::vector<StageConfig> stages;
    for (size_t i = 0; i < message.stages().size(); ++i) {
      const msg::Stage& s = message.stages()[i];
      const std::string path = fmt::format("device.stages[{}]", i);
      StageConfig stage;
      switch (s.kind()) {
        case msg::STAGE_FIXED_AXIS: stage.kind = StageConfig::Kind::kFixedAxis; break;
        case msg::STAGE_ADJUSTABLE_AXIS: stage.kind = StageConfig::Kind::kAdjustableAxis; break;
        default:
          return fmt::format("{}.kind: unknown stage kind {}", path, static_cast<int>(s.kind()));
      }
      stage.name = s.name().to_string();
      stage.axis = Vector3(s.axis()[0], s.axis()[1], s.axis()[2]);
      stage.map = MapConfig(s.control_map(), path + ".map");
      stage.range = RangeConfig(s.range());
      stage.retardance = AngleConfig(s.retardance(), path + ".retardance");
      stage.orientation = AngleConfig(s.orientation(), path + ".orientation");
      stages.push_back(std::move(stage));
    }
    ValidateDeviceStages(stages);
    if (const int controls = ScenarioControlCount(stages); controls > static_cast<int>(msg::MAX_CONTROLS)) {
      return fmt::format("device: {} controls, more than the {} a command can carry (oversized)", controls,
                         msg::MAX_CONTROLS);
    }
    if (!(std::isfinite(message.max_slew_per_s()) && message.max_slew_per_s() >= 0.0)) {
      return fmt::format("max_slew_per_s = {} is not a finite rate >= 0", message.max_slew_per_s());
    }
    if (!(std::isfinite(message.max_ramp_s()) && message.max_ramp_s() >= 0.0)) {
      return fmt::format("max_ramp_s = {} is not a finite duration >= 0", message.max_ramp_s());
    }
    out->driver_id = message.driver_id().to_string();
    out->stages = std::move(stages);
    out->max_slew_per_s = message.max_slew_per_s();
    out->max_ramp_s = message.max_ramp_s();
    return {};
  } catch (const std::invalid_argument& e) {  // ScenarioError names the field
    return e.what();
  }
}

msg::Target TargetMessage(const BenchTarget& target, const std::string& bench_id) {
  msg::Target out;
  out.bench_id(bench_id);
  out.revision(target.revision);
  out.request_id(target.request_id);
  out.kind(target.target.kind == TargetConfig::Kind::kPoint ? msg::TARGET_POINT : msg::TARGET_SET);
  out.point(ToArray(target.target.point));
  out.normal(ToArray(target.target.normal));
  out.offset(target.target.offset);
  return out;
}

namespace {

template <typename Message>
TargetConfig TargetConfigOf(const Message& message) {
  TargetConfig target;
  switch (message.kind()) {
    case msg::TARGET_POINT: target.kind = TargetConfig::Kind::kPoint; break;
    case msg::TARGET_SET: target.kind = TargetConfig::Kind::kSet; break;
    default:
      throw std::invalid_argument(
          fmt::format("target.kind: unknown target kind {}", static_cast<int>(message.kind())));
  }
  target.point = ToStokes(message.point());
  target.normal = Vector3(message.normal()[0], message.normal()[1], message.normal()[2]);
  target.offset = message.offset();
  ValidateTargetConfig(target);
  return target;
}

}  // namespace

std::string ReadTarget(const msg::Target& message, BenchTarget* out) {
  try {
    out->target = TargetConfigOf(message);
    out->revision = message.revision();
    out->request_id = message.request_id().to_string();
    return {};
  } catch (const std::invalid_argument& e) {  // ScenarioError names the field
    return e.what();
  }
}

TargetConfig TargetFromRequest(const msg::TargetRequest& request) { return TargetConfigOf(request); }

std::string PrintableText(std::string text) {
  for (char& c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) c = '?';
  }
  return text;
}

msg::ControllerStatus StatusMessage(const ControllerStatusReport& status, const std::string& bench_id) {
  msg::ControllerStatus out;
  out.bench_id(bench_id);
  out.controller_id(status.controller_id.substr(0, 63));
  out.priority(status.priority);
  out.law(status.law.substr(0, 31));
  out.obeyed(status.obeyed);
  out.condition(status.condition.substr(0, 127));
  out.answers_sample(status.answers_sample);
  out.error_deg(status.error_deg);
  out.sigma_max(status.sigma_max);
  out.sigma_min(status.sigma_min);
  out.nullspace_active_fraction(status.nullspace_active_fraction);
  out.compute_time_mean_s(status.compute_time_mean_s);
  out.compute_time_max_s(status.compute_time_max_s);
  out.updates(status.updates);
  out.failed_updates(status.failed_updates);
  out.rejected_samples(status.rejected_samples);
  out.missed_deadlines(status.missed_deadlines);
  out.last_rejection(status.last_rejection.substr(0, 255));
  out.publish_time_ns(status.publish_time_ns);
  return out;
}

std::string ReadStatus(const msg::ControllerStatus& m, ControllerStatusReport* out) {
  const std::pair<const char*, double> figures[] = {
      {"error_deg", m.error_deg()},
      {"sigma_max", m.sigma_max()},
      {"sigma_min", m.sigma_min()},
      {"nullspace_active_fraction", m.nullspace_active_fraction()},
      {"compute_time_mean_s", m.compute_time_mean_s()},
      {"compute_time_max_s", m.compute_time_max_s()}};
  for (const auto& [name, value] : figures) {
    if (!std::isfinite(value) || value < 0.0) return fmt::format("{} = {} (finite, >= 0)", name, value);
  }
  if (m.error_deg() > 180.0) return fmt::format("error_deg = {} (at most 180)", m.error_deg());
  if (m.nullspace_active_fraction() > 1.0) {
    return fmt::format("nullspace_active_fraction = {} (at most 1)", m.nullspace_active_fraction());
  }
  if (m.controller_id().size() == 0) return "no controller_id";
  out->controller_id = PrintableText(m.controller_id().to_string());
  out->priority = m.priority();
  out->law = PrintableText(m.law().to_string());
  out->obeyed = m.obeyed();
  out->condition = PrintableText(m.condition().to_string());
  out->answers_sample = m.answers_sample();
  out->error_deg = m.error_deg();
  out->sigma_max = m.sigma_max();
  out->sigma_min = m.sigma_min();
  out->nullspace_active_fraction = m.nullspace_active_fraction();
  out->compute_time_mean_s = m.compute_time_mean_s();
  out->compute_time_max_s = m.compute_time_max_s();
  out->updates = m.updates();
  out->failed_updates = m.failed_updates();
  out->rejected_samples = m.rejected_samples();
  out->missed_deadlines = m.missed_deadlines();
  out->last_rejection = PrintableText(m.last_rejection().to_string());
  out->publish_time_ns = m.publish_time_ns();
  return {};
}

}  // namespace dpc::bus

namespace dpc::bus {

void WriteSummary(const BenchSummary& summary, const std::string& bench_id, msg::BenchSummary* out) {
  out->bench_id(bench_id);
  out->sequence_number(summary.sequence);
  out->publish_time_ns(summary.publish_time_ns);
  out->period_s(summary.period_s);
  out->samples(summary.samples);
  out->last_sample(summary.last_sample);
  out->s_in(ToArray(summary.s_in));
  out->s_out(ToArray(summary.s_out));
  out->trail().clear();
  for (size_t i = 0; i < summary.trail.size() && i < kMaxSummaryTrailPoints; ++i) {
    out->trail().insert(out->trail().end(), summary.trail[i].begin(), summary.trail[i].end());
  }
  out->error_known(summary.error_mean_deg.has_value());
  out->error_mean_deg(summary.error_mean_deg.value_or(0.0));
  out->error_max_deg(summary.error_mean_deg ? summary.error_max_deg : 0.0);
  out->latencies(summary.latencies);
  out->latency_p50_us(summary.latency_p50_us);
  out->latency_p90_us(summary.latency_p90_us);
  out->latency_p99_us(summary.latency_p99_us);
  out->latency_max_us(summary.latency_max_us);
  out->state_known(summary.state.has_value());
  if (summary.state) {
    const DriverState& state = *summary.state;
    out->mode(state.mode == DriverMode::kActive ? msg::DRIVER_ACTIVE : msg::DRIVER_HOLDING);
    out->reason(state.reason.substr(0, 255));
    out->obeyed_controller_id(state.obeyed_controller_id.substr(0, 63));
    out->obeyed_priority(state.obeyed_priority);
    out->phi_applied().assign(state.motion.phi.data(), state.motion.phi.data() + state.motion.phi.size());
    out->saturated().assign(state.saturated.begin(), state.saturated.begin() + state.control_count());
    out->commands_applied(state.commands_applied);
    out->commands_rejected(state.commands_rejected);
    out->commands_limited(state.commands_limited);
    out->controller_switches(state.controller_switches);
  } else {
    out->mode(msg::DRIVER_HOLDING);
    out->reason("");
    out->obeyed_controller_id("");
    out->obeyed_priority(0);
    out->phi_applied().clear();
    out->saturated().clear();
    out->commands_applied(0);
    out->commands_rejected(0);
    out->commands_limited(0);
    out->controller_switches(0);
  }
}

std::string ReadSummary(const msg::BenchSummary& m, BenchSummary* out) {
  const double figures[] = {m.period_s(),       m.error_mean_deg(), m.error_max_deg(),  m.latency_p50_us(),
                            m.latency_p90_us(), m.latency_p99_us(), m.latency_max_us()};
  for (double v : figures) {
    if (!std::isfinite(v) || v < 0.0) return fmt::format("a figure is {} (negative or not finite)", v);
  }
  if (m.sequence_number() == 0) return "sequence_number 0";
  if (m.last_sample() != 0) {
    if (std::string reason = CheckUnitStokes(m.s_in(), "s_in"); !reason.empty()) return reason;
    if (std::string reason = CheckUnitStokes(m.s_out(), "s_out"); !reason.empty()) return reason;
  }
  if (m.trail().size() % 6 != 0 || m.trail().size() > 6 * kMaxSummaryTrailPoints) {
    return fmt::format("the trail has {} values, not whole points of 6 (at most {})", m.trail().size(),
                       6 * kMaxSummaryTrailPoints);
  }
  for (size_t i = 0; i < m.trail().size(); i += 3) {
    const std::array<double, 3> point{m.trail()[i], m.trail()[i + 1], m.trail()[i + 2]};
    if (std::string reason = CheckUnitStokes(point, "trail"); !reason.empty()) return reason;
  }
  if (m.state_known()) {
    if (m.phi_applied().size() > msg::MAX_CONTROLS) return "phi_applied: more values than any device has (oversized)";
    if (std::string reason = CheckFinite(m.phi_applied(), "phi_applied"); !reason.empty()) return reason;
    if (m.saturated().size() != m.phi_applied().size()) {
      return fmt::format("saturated has {} values, phi_applied {}", m.saturated().size(), m.phi_applied().size());
    }
    if (m.mode() != msg::DRIVER_ACTIVE && m.mode() != msg::DRIVER_HOLDING) {
      return fmt::format("mode {} is not a driver mode", static_cast<int>(m.mode()));
    }
  }
  out->sequence = m.sequence_number();
  out->publish_time_ns = m.publish_time_ns();
  out->period_s = m.period_s();
  out->samples = m.samples();
  out->last_sample = m.last_sample();
  out->s_in = ToStokes(m.s_in());
  out->s_out = ToStokes(m.s_out());
  out->trail.clear();
  for (size_t i = 0; i < m.trail().size(); i += 6) {
    out->trail.push_back({m.trail()[i], m.trail()[i + 1], m.trail()[i + 2], m.trail()[i + 3], m.trail()[i + 4],
                          m.trail()[i + 5]});
  }
  out->error_mean_deg.reset();
  if (m.error_known()) out->error_mean_deg = m.error_mean_deg();
  out->error_max_deg = m.error_max_deg();
  out->latencies = m.latencies();
  out->latency_p50_us = m.latency_p50_us();
  out->latency_p90_us = m.latency_p90_us();
  out->latency_p99_us = m.latency_p99_us();
  out->latency_max_us = m.latency_max_us();
  out->state.reset();
  if (m.state_known()) {
    DriverState state;
    const auto controls = static_cast<Eigen::Index>(m.phi_applied().size());
    state.motion = WaveplateMotion::Still(ControlVector::Zero(controls));
    for (Eigen::Index i = 0; i < controls; ++i) state.motion.phi[i] = m.phi_applied()[static_cast<size_t>(i)];
    for (size_t i = 0; i < m.saturated().size(); ++i) state.saturated[i] = m.saturated()[i];
    state.mode = m.mode() == msg::DRIVER_ACTIVE ? DriverMode::kActive : DriverMode::kHolding;
    state.reason = m.reason().to_string();
    state.obeyed_controller_id = m.obeyed_controller_id().to_string();
    state.obeyed_priority = m.obeyed_priority();
    state.commands_applied = m.commands_applied();
    state.commands_rejected = m.commands_rejected();
    state.commands_limited = m.commands_limited();
    state.controller_switches = m.controller_switches();
    out->state = std::move(state);
  }
  return {};
}

}  // namespace dpc::bus
