#include "dpc/bus/message_conversion.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "dpc/config/scenario_validation.h"

namespace dpc::bus {
namespace {

msg::ControlMap MapMessage(const ControlMapConfig& map) {
  msg::ControlMap out;
  switch (map.kind) {
    case ControlMapConfig::Kind::kLinear: out.kind(msg::MAP_LINEAR); break;
    case ControlMapConfig::Kind::kPolynomial: out.kind(msg::MAP_POLYNOMIAL); break;
    case ControlMapConfig::Kind::kTable: out.kind(msg::MAP_TABLE); break;
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
  out.rad_per_unit = map.rad_per_unit();
  out.offset_rad = map.offset_rad();
  out.coefficients_rad = map.coefficients_rad();
  out.table_control = map.table_control();
  out.table_angle_rad = map.table_angle_rad();
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

std::string CheckStokesSample(const msg::StokesSample& sample) {
  if (sample.sequence_number() == 0) return "sequence_number 0 (sequences start at 1)";
  if (std::string reason = CheckUnitStokes(sample.s_in(), "s_in"); !reason.empty()) return reason;
  if (std::string reason = CheckUnitStokes(sample.s_out(), "s_out"); !reason.empty()) return reason;
  if (sample.optical_power_known() &&
      !(std::isfinite(sample.optical_power_w()) && sample.optical_power_w() >= 0.0)) {
    return fmt::format("optical_power_w = {} is not a finite power >= 0", sample.optical_power_w());
  }
  return {};
}

std::string CheckCommandShape(const msg::WaveplateCommand& command, int control_count) {
  const size_t count = command.phi().size();
  if (command.controller_id().size() == 0) return "empty controller_id";
  if (count > msg::MAX_CONTROLS) {
    return fmt::format("phi has {} values, more than the {} any device may have (oversized)",
                       count, msg::MAX_CONTROLS);
  }
  if (count != static_cast<size_t>(control_count)) {
    return fmt::format("phi has {} values, the device has {} controls", count, control_count);
  }
  if (std::string reason = CheckFinite(command.phi(), "phi"); !reason.empty()) return reason;
  return CheckRates(command.phi_rate_per_s(), count);
}

std::string CheckStateShape(const msg::WaveplateState& state, int control_count) {
  const size_t controls = static_cast<size_t>(control_count);
  if (state.phi_applied().size() != controls) {
    return fmt::format("phi_applied has {} values, the device has {} controls",
                       state.phi_applied().size(), controls);
  }
  if (std::string reason = CheckFinite(state.phi_applied(), "phi_applied"); !reason.empty()) return reason;
  if (std::string reason = CheckRates(state.phi_rate_per_s(), controls); !reason.empty()) return reason;
  if (state.mode() != msg::DRIVER_ACTIVE && state.mode() != msg::DRIVER_HOLDING) {
    return fmt::format("mode {} is not a driver mode", static_cast<int>(state.mode()));
  }
  if (!state.phi_rate_per_s().empty()) {
    if (state.ramp_end_time_ns() < state.ramp_start_time_ns()) {
      return fmt::format("ramp_end_time_ns {} is before ramp_start_time_ns {}", state.ramp_end_time_ns(),
                         state.ramp_start_time_ns());
    }
    // Overflow-safe: the difference of two arbitrary int64 does not fit an int64.
    const uint64_t ramp_ns = static_cast<uint64_t>(state.ramp_end_time_ns()) -
                             static_cast<uint64_t>(state.ramp_start_time_ns());
    if (ramp_ns > kMaxRampNs) {
      return fmt::format("the ramp lasts {} ns, longer than any driver ramps ({} ns)", ramp_ns, kMaxRampNs);
    }
  }
  return {};
}

void ReadTrajectory(const msg::WaveplateState& state, AppliedTrajectory* out) {
  const int n = static_cast<int>(state.phi_applied().size());
  if (out->phi.size() != n) out->phi.resize(n);
  if (out->rate_per_s.size() != n) out->rate_per_s.resize(n);
  bool moving = false;
  for (int i = 0; i < n; ++i) {
    out->phi[i] = state.phi_applied()[static_cast<size_t>(i)];
    const double rate = state.phi_rate_per_s().empty() ? 0.0 : state.phi_rate_per_s()[static_cast<size_t>(i)];
    out->rate_per_s[i] = rate;
    moving = moving || rate != 0.0;
  }
  out->start_ns = state.ramp_start_time_ns();
  out->end_ns = state.ramp_end_time_ns();
  out->moving = moving && out->end_ns > out->start_ns;
}

msg::DeviceDescription DescribeDevice(const std::vector<StageConfig>& stages,
                                      const std::string& bench_id, const std::string& driver_id,
                                      double max_slew_per_s, double max_ramp_s) {
  msg::DeviceDescription out;
  out.bench_id(bench_id);
  out.driver_id(driver_id);
  out.max_slew_per_s(max_slew_per_s);
  out.max_ramp_s(max_ramp_s);
  for (const StageConfig& stage : stages) {
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

std::vector<StageConfig> StagesFromDescription(const msg::DeviceDescription& description) {
  std::vector<StageConfig> stages;
  for (size_t i = 0; i < description.stages().size(); ++i) {
    const msg::Stage& s = description.stages()[i];
    const std::string path = fmt::format("device.stages[{}]", i);
    StageConfig stage;
    switch (s.kind()) {
      case msg::STAGE_FIXED_AXIS: stage.kind = StageConfig::Kind::kFixedAxis; break;
      case msg::STAGE_ADJUSTABLE_AXIS: stage.kind = StageConfig::Kind::kAdjustableAxis; break;
      default:
        throw std::invalid_argument(fmt::format("{}.kind: unknown stage kind {}", path,
                                                static_cast<int>(s.kind())));
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
  return stages;
}

msg::Target TargetMessage(const TargetConfig& target, const std::string& bench_id,
                          uint64_t revision, const std::string& request_id) {
  msg::Target out;
  out.bench_id(bench_id);
  out.revision(revision);
  out.request_id(request_id);
  out.kind(target.kind == TargetConfig::Kind::kPoint ? msg::TARGET_POINT : msg::TARGET_SET);
  out.point(ToArray(target.point));
  out.normal(ToArray(target.normal));
  out.offset(target.offset);
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

TargetConfig TargetFromMessage(const msg::Target& message) { return TargetConfigOf(message); }
TargetConfig TargetFromRequest(const msg::TargetRequest& request) { return TargetConfigOf(request); }

}  // namespace dpc::bus
