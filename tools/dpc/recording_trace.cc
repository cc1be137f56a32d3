#include "recording_trace.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "dpc/bench/bench_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/control/target.h"
#include "dpc/optics/waveplate_chain.h"
#include "dpc/record/mcap.h"
#include "dpc/sim/trace_header.h"
#include "dpc/sim/trace_writer.h"

namespace dpc::tools {
namespace {

constexpr uint64_t kReorderWindowNs = 1'000'000'000;
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

/// What the first pass learns: the device, the controls, the first sample's log time, the
/// driver's holding intervals and the controller switches (in log time).
struct Overview {
  std::optional<WaveplateChain> chain;
  std::string bench_id;
  std::optional<uint64_t> first_sample_ns;
  int state_controls = -1;  ///< φ count of the first valid state
  std::optional<StokesVector> first_target_point;
  bool holding = false;
  std::optional<uint64_t> hold_start_ns;
  std::vector<std::pair<uint64_t, uint64_t>> holds_ns;
  std::vector<std::pair<uint64_t, std::string>> switches_ns;
  std::string obeyed;  ///< the controller obeyed last (while active)
  uint64_t last_ns = 0;
  uint64_t skipped = 0;
};

}  // namespace

RecordingFigure WriteRecordingTrace(const std::string& mcap_path, const std::string& trace_csv) {
  Overview o;
  const auto first = record::ReadMcapInLogTimeOrder(
      mcap_path, kReorderWindowNs, [&](const record::McapChannel& channel, const record::McapMessage& m) {
        o.last_ns = std::max(o.last_ns, m.log_time_ns);
        if (channel.topic == bus::TopicTraits<msg::StokesSample>::kTopic) {
          msg::StokesSample message;
          BenchSample sample;
          if (!bus::DecodeRaw(m.data, &message) || !bus::ReadSample(message, &sample).empty()) {
            ++o.skipped;
            return;
          }
          if (!o.first_sample_ns) {
            o.first_sample_ns = m.log_time_ns;
            o.bench_id = message.bench_id().to_string();
          }
        } else if (channel.topic == bus::TopicTraits<msg::DeviceDescription>::kTopic && !o.chain) {
          msg::DeviceDescription message;
          DeviceDescription device;
          if (!bus::DecodeRaw(m.data, &message) || !bus::ReadDevice(message, &device).empty()) {
            ++o.skipped;
            return;
          }
          try {
            o.chain = BuildChain(device.stages);
          } catch (const std::exception&) {
            ++o.skipped;
          }
        } else if (channel.topic == bus::TopicTraits<msg::Target>::kTopic && !o.first_target_point) {
          msg::Target message;
          BenchTarget target;
          if (!bus::DecodeRaw(m.data, &message) || !bus::ReadTarget(message, &target).empty()) {
            ++o.skipped;
            return;
          }
          const Target built = BuildTarget(target.target);
          if (built.is_point()) o.first_target_point = built.point();
        } else if (channel.topic == bus::TopicTraits<msg::WaveplateState>::kTopic) {
          msg::WaveplateState message;
          DriverState state;
          if (!bus::DecodeRaw(m.data, &message) ||
              !bus::ReadState(message, static_cast<int>(message.phi_applied().size()), &state).empty()) {
            ++o.skipped;
            return;
          }
          if (o.state_controls < 0) o.state_controls = static_cast<int>(message.phi_applied().size());
          const bool holding = state.mode == DriverMode::kHolding;
          if (holding && !o.holding) o.hold_start_ns = m.log_time_ns;
          if (!holding && o.holding && o.hold_start_ns) o.holds_ns.emplace_back(*o.hold_start_ns, m.log_time_ns);
          o.holding = holding;
          if (!holding && !state.obeyed_controller_id.empty()) {
            if (!o.obeyed.empty() && state.obeyed_controller_id != o.obeyed) {
              o.switches_ns.emplace_back(m.log_time_ns, state.obeyed_controller_id);
            }
            o.obeyed = state.obeyed_controller_id;
          }
        }
      });
  if (o.holding && o.hold_start_ns) o.holds_ns.emplace_back(*o.hold_start_ns, o.last_ns);
  if (!o.first_sample_ns) {
    throw std::runtime_error(fmt::format("{} holds no usable polarimeter sample (dpc_stokes_sample){}", mcap_path,
                                         first.problem.empty() ? "" : "; reading stopped at " + first.problem));
  }

  RecordingFigure figure;
  figure.skipped = o.skipped;
  // The controls: the device's (names and ranges), else as many as the states carry.
  std::vector<std::string> names;
  if (o.chain) {
    for (const auto& control : o.chain->controls()) names.push_back(control.name);
    if (o.state_controls >= 0 && o.state_controls != static_cast<int>(names.size())) {
      figure.notes.push_back(fmt::format("the states carry {} controls, the device description {}: φ not drawn",
                                         o.state_controls, names.size()));
      names.clear();
    } else if (o.chain->has_ranges()) {
      for (size_t i = 0; i < o.chain->range_min().size(); ++i) {
        figure.options.control_ranges.emplace_back(o.chain->range_min()[i], o.chain->range_max()[i]);
      }
    }
  } else {
    figure.notes.push_back("no device description recorded: the controls are numbered");
    for (int i = 0; i < std::max(o.state_controls, 0); ++i) names.push_back(fmt::format("phi_{}", i + 1));
  }
  if (o.state_controls < 0) figure.notes.push_back("no driver state recorded: φ not drawn");

  const auto seconds = [&](uint64_t ns) {
    return (static_cast<double>(ns) - static_cast<double>(*o.first_sample_ns)) / 1e9;
  };
  figure.options.title = fmt::format("recording {}: bench {}{}", std::filesystem::path(mcap_path).filename().string(),
                                     o.bench_id,
                                     o.chain ? fmt::format(", M = {} (light: {})", o.chain->PaperNotation(),
                                                           o.chain->Describe())
                                             : "");
  figure.options.target_point = o.first_target_point;
  for (const auto& [from, to] : o.holds_ns) figure.options.shaded_intervals.emplace_back(seconds(from), seconds(to));
  for (const auto& [at, controller] : o.switches_ns) figure.options.events.push_back({seconds(at), "→ " + controller});
  figure.options.time_scale = 1.0;
  figure.options.time_unit = "s";

  // Second pass: the rows.
  std::vector<std::string> header{kTraceMagic, "title=" + figure.options.title, "producer=dpc plot (from " +
                                  std::filesystem::path(mcap_path).filename().string() + ")"};
  TraceWriter trace(trace_csv, names, header);
  std::optional<Target> target;
  ControlVector phi = ControlVector::Constant(static_cast<Eigen::Index>(names.size()),
                                              std::numeric_limits<double>::quiet_NaN());
  record::ReadMcapInLogTimeOrder(
      mcap_path, kReorderWindowNs, [&](const record::McapChannel& channel, const record::McapMessage& m) {
        if (channel.topic == bus::TopicTraits<msg::Target>::kTopic) {
          msg::Target message;
          BenchTarget t;
          if (bus::DecodeRaw(m.data, &message) && bus::ReadTarget(message, &t).empty()) target = BuildTarget(t.target);
        } else if (channel.topic == bus::TopicTraits<msg::WaveplateState>::kTopic) {
          msg::WaveplateState message;
          DriverState state;
          if (bus::DecodeRaw(m.data, &message) && message.phi_applied().size() == names.size() &&
              bus::ReadState(message, static_cast<int>(names.size()), &state).empty()) {
            for (size_t i = 0; i < names.size(); ++i) phi[static_cast<Eigen::Index>(i)] = message.phi_applied()[i];
          }
        } else if (channel.topic == bus::TopicTraits<msg::StokesSample>::kTopic) {
          msg::StokesSample message;
          BenchSample sample;
          if (!bus::DecodeRaw(m.data, &message) || !bus::ReadSample(message, &sample).empty()) return;
          const double error_deg = target ? target->DistanceRad(sample.s_out) * kDegPerRad
                                          : std::numeric_limits<double>::quiet_NaN();
          trace.Write(seconds(m.log_time_ns), sample.s_in, sample.s_out, error_deg, phi);
          ++figure.samples;
        }
      });
  trace.Flush();
  if (!first.complete) figure.notes.push_back("the recording is cut short (" + first.problem + "): drawn up to there");
  return figure;
}

}  // namespace dpc::tools
