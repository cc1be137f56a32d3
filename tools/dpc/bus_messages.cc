#include "bus_messages.h"

#include <fmt/format.h>

#include <cmath>

namespace dpc::tools {
namespace {

using Json = nlohmann::ordered_json;

template <typename Message>
BusTopic TopicOf(std::string_view alias, std::string_view type_name) {
  return {bus::TopicTraits<Message>::kTopic, alias, type_name};
}

Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

template <typename Container>
Json Numbers(const Container& values) {
  Json out = Json::array();
  for (double v : values) out.push_back(Number(v));
  return out;
}

template <size_t N>
std::string Text(const eprosima::fastrtps::fixed_string<N>& s) {
  return s.to_string();
}

std::string Values(const std::vector<double>& v, int decimals = 4) {
  return FormatValues(v.data(), v.size(), decimals);
}
std::string Values(const std::array<double, 3>& v, int decimals = 4) {
  return FormatValues(v.data(), v.size(), decimals);
}

double Seconds(int64_t ns) { return static_cast<double>(ns) * 1e-9; }

Json MapJson(const msg::ControlMap& m) {
  return Json{{"kind", ControlMapKindName(m.kind())},
              {"rad_per_unit", Number(m.rad_per_unit())},
              {"offset_rad", Number(m.offset_rad())},
              {"coefficients_rad", Numbers(m.coefficients_rad())},
              {"table_control", Numbers(m.table_control())},
              {"table_angle_rad", Numbers(m.table_angle_rad())}};
}

Json RangeJson(const msg::ControlRange& r) {
  return Json{{"limited", r.limited()}, {"min_phi", Number(r.min_phi())}, {"max_phi", Number(r.max_phi())}};
}

Json AngleJson(const msg::StageAngle& a) {
  return Json{{"controlled", a.controlled()},
              {"fixed_rad", Number(a.fixed_rad())},
              {"control_map", MapJson(a.control_map())},
              {"range", RangeJson(a.range())}};
}

Json StageJson(const msg::Stage& s) {
  return Json{{"kind", StageKindName(s.kind())},
              {"name", Text(s.name())},
              {"axis", Numbers(s.axis())},
              {"control_map", MapJson(s.control_map())},
              {"range", RangeJson(s.range())},
              {"retardance", AngleJson(s.retardance())},
              {"orientation", AngleJson(s.orientation())}};
}

template <typename TargetLike>
std::string TargetShape(const TargetLike& m) {
  if (m.kind() == msg::TARGET_POINT) return "point " + Values(m.point());
  return fmt::format("set {}·S = {:.4f}", Values(m.normal()), m.offset());
}

}  // namespace

const std::vector<BusTopic>& BenchTopics() {
  static const std::vector<BusTopic> topics = {
      TopicOf<msg::StokesSample>("sample", "dpc::msg::StokesSample"),
      TopicOf<msg::WaveplateCommand>("command", "dpc::msg::WaveplateCommand"),
      TopicOf<msg::WaveplateState>("state", "dpc::msg::WaveplateState"),
      TopicOf<msg::ControllerStatus>("status", "dpc::msg::ControllerStatus"),
      TopicOf<msg::DeviceDescription>("device", "dpc::msg::DeviceDescription"),
      TopicOf<msg::Target>("target", "dpc::msg::Target"),
      TopicOf<msg::TargetRequest>("request", "dpc::msg::TargetRequest"),
      TopicOf<msg::TargetReply>("reply", "dpc::msg::TargetReply"),
      TopicOf<msg::BenchSummary>("summary", "dpc::msg::BenchSummary"),
  };
  return topics;
}

std::optional<BusTopic> ResolveTopic(std::string_view name) {
  for (const BusTopic& topic : BenchTopics()) {
    if (name == topic.name || name == topic.alias || name == topic.name.substr(4)) return topic;
  }
  return std::nullopt;
}

std::string DescribeValidTopics() {
  std::string out;
  for (const BusTopic& topic : BenchTopics()) {
    if (!out.empty()) out += ", ";
    out += fmt::format("{} ({})", topic.name, topic.alias);
  }
  return out;
}

const char* DriverModeName(msg::DriverMode mode) {
  switch (mode) {
    case msg::DRIVER_ACTIVE: return "DRIVER_ACTIVE";
    case msg::DRIVER_HOLDING: return "DRIVER_HOLDING";
  }
  return "UNKNOWN";
}

const char* TargetKindName(msg::TargetKind kind) {
  switch (kind) {
    case msg::TARGET_POINT: return "TARGET_POINT";
    case msg::TARGET_SET: return "TARGET_SET";
  }
  return "UNKNOWN";
}

const char* ControlMapKindName(msg::ControlMapKind kind) {
  switch (kind) {
    case msg::MAP_LINEAR: return "MAP_LINEAR";
    case msg::MAP_POLYNOMIAL: return "MAP_POLYNOMIAL";
    case msg::MAP_TABLE: return "MAP_TABLE";
  }
  return "UNKNOWN";
}

const char* StageKindName(msg::StageKind kind) {
  switch (kind) {
    case msg::STAGE_FIXED_AXIS: return "STAGE_FIXED_AXIS";
    case msg::STAGE_ADJUSTABLE_AXIS: return "STAGE_ADJUSTABLE_AXIS";
  }
  return "UNKNOWN";
}

std::string FormatValues(const double* values, size_t count, int decimals) {
  std::string out = "[";
  for (size_t i = 0; i < count; ++i) {
    if (i > 0) out += ", ";
    out += fmt::format("{:+.{}f}", values[i], decimals);
  }
  return out + "]";
}

// ---- JSON: every field, IDL order.

Json ToJson(const msg::StokesSample& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"sequence_number", m.sequence_number()},
              {"sample_time_ns", m.sample_time_ns()},
              {"publish_time_ns", m.publish_time_ns()},
              {"s_in", Numbers(m.s_in())},
              {"s_out", Numbers(m.s_out())},
              {"optical_power_known", m.optical_power_known()},
              {"optical_power_w", Number(m.optical_power_w())},
              {"lockstep", m.lockstep()}};
}

Json ToJson(const msg::WaveplateCommand& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"controller_id", Text(m.controller_id())},
              {"priority", m.priority()},
              {"sequence_number", m.sequence_number()},
              {"answers_sample", m.answers_sample()},
              {"sample_time_ns", m.sample_time_ns()},
              {"sample_publish_time_ns", m.sample_publish_time_ns()},
              {"publish_time_ns", m.publish_time_ns()},
              {"phi", Numbers(m.phi())},
              {"phi_rate_per_s", Numbers(m.phi_rate_per_s())}};
}

Json ToJson(const msg::WaveplateState& m) {
  Json saturated = Json::array();
  for (bool b : m.saturated()) saturated.push_back(b);
  return Json{{"bench_id", Text(m.bench_id())},
              {"sequence_number", m.sequence_number()},
              {"answers_sample", m.answers_sample()},
              {"sample_time_ns", m.sample_time_ns()},
              {"sample_publish_time_ns", m.sample_publish_time_ns()},
              {"command_receive_time_ns", m.command_receive_time_ns()},
              {"publish_time_ns", m.publish_time_ns()},
              {"phi_applied", Numbers(m.phi_applied())},
              {"phi_rate_per_s", Numbers(m.phi_rate_per_s())},
              {"ramp_start_time_ns", m.ramp_start_time_ns()},
              {"ramp_end_time_ns", m.ramp_end_time_ns()},
              {"saturated", saturated},
              {"mode", DriverModeName(m.mode())},
              {"reason", Text(m.reason())},
              {"obeyed_controller_id", Text(m.obeyed_controller_id())},
              {"obeyed_priority", m.obeyed_priority()},
              {"commands_applied", m.commands_applied()},
              {"commands_rejected", m.commands_rejected()},
              {"commands_limited", m.commands_limited()},
              {"controller_switches", m.controller_switches()},
              {"last_rejection", Text(m.last_rejection())},
              {"applied_controller_id", Text(m.applied_controller_id())},
              {"stand_ins", m.stand_ins()}};
}

Json ToJson(const msg::ControllerStatus& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"controller_id", Text(m.controller_id())},
              {"priority", m.priority()},
              {"law", Text(m.law())},
              {"obeyed", m.obeyed()},
              {"condition", Text(m.condition())},
              {"answers_sample", m.answers_sample()},
              {"error_deg", Number(m.error_deg())},
              {"sigma_max", Number(m.sigma_max())},
              {"sigma_min", Number(m.sigma_min())},
              {"nullspace_active_fraction", Number(m.nullspace_active_fraction())},
              {"compute_time_mean_s", Number(m.compute_time_mean_s())},
              {"compute_time_max_s", Number(m.compute_time_max_s())},
              {"updates", m.updates()},
              {"failed_updates", m.failed_updates()},
              {"rejected_samples", m.rejected_samples()},
              {"missed_deadlines", m.missed_deadlines()},
              {"last_rejection", Text(m.last_rejection())},
              {"publish_time_ns", m.publish_time_ns()}};
}

Json ToJson(const msg::DeviceDescription& m) {
  Json stages = Json::array();
  for (const msg::Stage& s : m.stages()) stages.push_back(StageJson(s));
  return Json{{"bench_id", Text(m.bench_id())},
              {"driver_id", Text(m.driver_id())},
              {"stages", stages},
              {"max_slew_per_s", Number(m.max_slew_per_s())},
              {"max_ramp_s", Number(m.max_ramp_s())}};
}

Json ToJson(const msg::Target& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"revision", m.revision()},
              {"request_id", Text(m.request_id())},
              {"kind", TargetKindName(m.kind())},
              {"point", Numbers(m.point())},
              {"normal", Numbers(m.normal())},
              {"offset", Number(m.offset())}};
}

Json ToJson(const msg::TargetRequest& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"request_id", Text(m.request_id())},
              {"kind", TargetKindName(m.kind())},
              {"point", Numbers(m.point())},
              {"normal", Numbers(m.normal())},
              {"offset", Number(m.offset())}};
}

Json ToJson(const msg::BenchSummary& m) {
  Json saturated = Json::array();
  for (bool b : m.saturated()) saturated.push_back(b);
  return Json{{"bench_id", Text(m.bench_id())},
              {"sequence_number", m.sequence_number()},
              {"publish_time_ns", m.publish_time_ns()},
              {"period_s", Number(m.period_s())},
              {"samples", m.samples()},
              {"last_sample", m.last_sample()},
              {"s_in", Numbers(m.s_in())},
              {"s_out", Numbers(m.s_out())},
              {"trail", Numbers(m.trail())},
              {"error_known", m.error_known()},
              {"error_mean_deg", Number(m.error_mean_deg())},
              {"error_max_deg", Number(m.error_max_deg())},
              {"latencies", m.latencies()},
              {"latency_p50_us", Number(m.latency_p50_us())},
              {"latency_p90_us", Number(m.latency_p90_us())},
              {"latency_p99_us", Number(m.latency_p99_us())},
              {"latency_max_us", Number(m.latency_max_us())},
              {"state_known", m.state_known()},
              {"mode", DriverModeName(m.mode())},
              {"reason", Text(m.reason())},
              {"obeyed_controller_id", Text(m.obeyed_controller_id())},
              {"obeyed_priority", m.obeyed_priority()},
              {"phi_applied", Numbers(m.phi_applied())},
              {"saturated", std::move(saturated)},
              {"commands_applied", m.commands_applied()},
              {"commands_rejected", m.commands_rejected()},
              {"commands_limited", m.commands_limited()},
              {"controller_switches", m.controller_switches()}};
}

Json ToJson(const msg::TargetReply& m) {
  return Json{{"bench_id", Text(m.bench_id())},
              {"request_id", Text(m.request_id())},
              {"accepted", m.accepted()},
              {"message", Text(m.message())},
              {"revision", m.revision()}};
}

// ---- Text: one line each.

std::string ToText(const msg::StokesSample& m) {
  std::string power = m.optical_power_known() ? fmt::format(" power_w={:.4g}", m.optical_power_w()) : "";
  return fmt::format("[{}] sample #{} t={:.6f} s s_in={} s_out={}{}{}", Text(m.bench_id()),
                     m.sequence_number(), Seconds(m.sample_time_ns()), Values(m.s_in()),
                     Values(m.s_out()), power, m.lockstep() ? " lockstep" : "");
}

std::string ToText(const msg::WaveplateCommand& m) {
  return fmt::format("[{}] command from {} (priority {}) #{} answers sample #{} t={:.6f} s phi={}{}",
                     Text(m.bench_id()), Text(m.controller_id()), m.priority(), m.sequence_number(),
                     m.answers_sample(), Seconds(m.sample_time_ns()), Values(m.phi()),
                     m.phi_rate_per_s().empty() ? "" : " phi_rate_per_s=" + Values(m.phi_rate_per_s()));
}

std::string ToText(const msg::WaveplateState& m) {
  std::string saturated;
  for (size_t i = 0; i < m.saturated().size(); ++i) {
    if (!m.saturated()[i]) continue;
    if (!saturated.empty()) saturated += ',';
    saturated += std::to_string(i);
  }
  const bool active = m.mode() == msg::DRIVER_ACTIVE;
  const std::string obeyed = Text(m.obeyed_controller_id());
  return fmt::format(
      "[{}] state #{} {} obeyed={} (priority {}) phi_applied={}{}{} answers sample #{} t={:.6f} s "
      "applied={} rejected={} limited={} switches={}{}{}",
      Text(m.bench_id()), m.sequence_number(), active ? "ACTIVE" : "HOLDING",
      obeyed.empty() ? "-" : obeyed, m.obeyed_priority(), Values(m.phi_applied()),
      m.phi_rate_per_s().empty()
          ? ""
          : fmt::format(" phi_rate_per_s={} ramp=[{:.6f}, {:.6f}] s", Values(m.phi_rate_per_s()),
                        Seconds(m.ramp_start_time_ns()), Seconds(m.ramp_end_time_ns())),
      saturated.empty() ? "" : " saturated=[" + saturated + "]", m.answers_sample(),
      Seconds(m.sample_time_ns()), m.commands_applied(), m.commands_rejected(),
      m.commands_limited(), m.controller_switches(),
      m.stand_ins() == 0 ? "" : fmt::format(" stand_ins={} (last from {})", m.stand_ins(), Text(m.applied_controller_id())),
      m.reason().size() == 0 ? "" : " reason=\"" + Text(m.reason()) + "\"");
}

std::string ToText(const msg::ControllerStatus& m) {
  return fmt::format(
      "[{}] controller {} (priority {}, {}) {} \"{}\" error_deg={:.4f} sigma=[{:.3g}, {:.3g}] "
      "compute_us mean={:.2f} max={:.2f} updates={} failed={} rejected_samples={} "
      "missed_deadlines={}",
      Text(m.bench_id()), Text(m.controller_id()), m.priority(), Text(m.law()),
      m.obeyed() ? "obeyed" : "standby", Text(m.condition()), m.error_deg(), m.sigma_max(),
      m.sigma_min(), m.compute_time_mean_s() * 1e6, m.compute_time_max_s() * 1e6, m.updates(),
      m.failed_updates(), m.rejected_samples(), m.missed_deadlines());
}

std::string ToText(const msg::DeviceDescription& m) {
  std::string stages;
  for (const msg::Stage& s : m.stages()) {
    if (!stages.empty()) stages += ", ";
    if (s.kind() == msg::STAGE_FIXED_AXIS) {
      stages += fmt::format("{} axis {}", Text(s.name()).empty() ? "fixed" : Text(s.name()),
                            Values(s.axis(), 3));
    } else {
      stages += (Text(s.name()).empty() ? "adjustable" : Text(s.name())) + " adjustable-axis";
    }
  }
  return fmt::format("[{}] device of driver {}: {} stages [{}] max_slew_per_s={:g} max_ramp_s={:g}",
                     Text(m.bench_id()), Text(m.driver_id()), m.stages().size(), stages,
                     m.max_slew_per_s(), m.max_ramp_s());
}

std::string ToText(const msg::Target& m) {
  const std::string request = Text(m.request_id());
  return fmt::format("[{}] target revision {}: {} (request {})", Text(m.bench_id()), m.revision(),
                     TargetShape(m), request.empty() ? "none: the scenario" : request);
}

std::string ToText(const msg::TargetRequest& m) {
  return fmt::format("[{}] target request {}: {}", Text(m.bench_id()), Text(m.request_id()),
                     TargetShape(m));
}

std::string ToText(const msg::BenchSummary& m) {
  const std::string error = m.error_known() ? fmt::format("{:.3f} (max {:.3f})", m.error_mean_deg(), m.error_max_deg())
                                            : std::string("-");
  const std::string latency = m.latencies() > 0 ? fmt::format("p50 {:.0f} p99 {:.0f}", m.latency_p50_us(),
                                                              m.latency_p99_us())
                                                : std::string("-");
  const std::string driver = m.state_known() ? fmt::format("{} phi={}", DriverModeName(m.mode()), Values(m.phi_applied()))
                                             : std::string("no state");
  return fmt::format("[{}] summary #{} {} samples in {:.3f} s error_deg={} loop_us={} trail={} {}", Text(m.bench_id()),
                     m.sequence_number(), m.samples(), m.period_s(), error, latency, m.trail().size() / 6, driver);
}

std::string ToText(const msg::TargetReply& m) {
  return fmt::format("[{}] target reply to {}: {} revision {} \"{}\"", Text(m.bench_id()),
                     Text(m.request_id()), m.accepted() ? "accepted" : "refused", m.revision(),
                     Text(m.message()));
}

}  // namespace dpc::tools
