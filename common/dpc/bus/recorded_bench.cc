#include "dpc/bus/recorded_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/topics.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/record/mcap.h"

namespace dpc::bus {
namespace {

/// The recorder writes in the order it drains its readers (every 20 ms): the messages are put
/// back in log-time order within this window.
constexpr uint64_t kReorderWindowNs = 1'000'000'000;

bool Is(const record::McapChannel& channel, std::string_view topic) { return channel.topic == topic; }

}  // namespace

double RecordedBench::SampleRateHz() const {
  if (samples.size() < 2) return 0.0;
  std::vector<double> per_sample_ns;
  per_sample_ns.reserve(samples.size() - 1);
  for (size_t i = 1; i < samples.size(); ++i) {
    const uint64_t steps = samples[i].sequence - samples[i - 1].sequence;  // ≥ 1: one run
    per_sample_ns.push_back(static_cast<double>(samples[i].time_ns - samples[i - 1].time_ns) /
                            static_cast<double>(steps));
  }
  auto middle = per_sample_ns.begin() + static_cast<std::ptrdiff_t>(per_sample_ns.size() / 2);
  std::nth_element(per_sample_ns.begin(), middle, per_sample_ns.end());
  return *middle > 0.0 ? 1e9 / *middle : 0.0;
}

RecordedInput RecordedBench::Input() const {
  RecordedInput input;
  input.source = path;
  if (samples.empty()) return input;
  input.sops.reserve(static_cast<size_t>(samples.back().sequence - samples.front().sequence + 1));
  for (size_t i = 0; i < samples.size(); ++i) {
    if (i > 0) {
      for (uint64_t n = samples[i - 1].sequence + 1; n < samples[i].sequence; ++n) {
        input.sops.push_back(samples[i - 1].s_in);
      }
    }
    input.sops.push_back(samples[i].s_in);
  }
  return input;
}

RecordedBench ReadRecordedBench(const std::string& path, const RecordedBenchOptions& options) {
  if (!(options.from_s >= 0.0) || !std::isfinite(options.from_s) || !(options.duration_s >= 0.0) ||
      !std::isfinite(options.duration_s)) {
    throw std::invalid_argument(fmt::format("{}: from {} s for {} s: a time is negative or not finite", path,
                                            options.from_s, options.duration_s));
  }
  RecordedBench r;
  r.path = path;
  const auto reject = [&](std::string_view topic, const std::string& why) {
    ++r.rejected;
    r.last_rejection = fmt::format("{}: {}", topic, why);
  };
  std::optional<int64_t> first_time_ns;  // the file's first sample's bench time
  bool run_ended = false;
  const auto from_ns = static_cast<int64_t>(std::llround(options.from_s * 1e9));
  const auto length_ns = static_cast<int64_t>(std::llround(options.duration_s * 1e9));
  msg::StokesSample sample_message;
  msg::WaveplateState state_message;
  BenchSample sample;
  DriverState state;

  const record::McapReadResult read = record::ReadMcapInLogTimeOrder(
      path, kReorderWindowNs, [&](const record::McapChannel& channel, const record::McapMessage& m) {
        if (Is(channel, TopicTraits<msg::StokesSample>::kTopic)) {
          if (run_ended) return;
          if (!DecodeRaw(m.data, &sample_message)) return reject(channel.topic, "does not decode");
          if (const std::string why = ReadSample(sample_message, &sample); !why.empty()) {
            return reject(channel.topic, why);
          }
          if (!first_time_ns) {
            first_time_ns = sample.time_ns;
            r.bench_id = sample_message.bench_id().to_string();
          }
          if (!r.samples.empty() && sample.sequence <= r.samples.back().sequence) {
            run_ended = r.later_runs = true;  // a restarted bench
            return;
          }
          const int64_t since_ns = sample.time_ns - *first_time_ns;
          if (since_ns < from_ns) return;
          if (length_ns > 0 && since_ns - from_ns >= length_ns) {
            run_ended = true;
            return;
          }
          if (!r.samples.empty()) r.samples_missing += sample.sequence - r.samples.back().sequence - 1;
          r.samples.push_back({m.log_time_ns, sample.sequence, sample.time_ns, sample.s_in, sample.s_out});
          return;
        }
        if (options.samples_only) return;
        if (Is(channel, TopicTraits<msg::WaveplateState>::kTopic)) {
          if (!DecodeRaw(m.data, &state_message)) return reject(channel.topic, "does not decode");
          const int controls = r.controls > 0 ? r.controls : static_cast<int>(state_message.phi_applied().size());
          if (const std::string why = ReadState(state_message, controls, &state); !why.empty()) {
            return reject(channel.topic, why);
          }
          r.controls = controls;
          r.states.push_back({m.log_time_ns, state.answers_sample, state.mode == DriverMode::kHolding,
                              r.state_phi.size()});
          for (int i = 0; i < controls; ++i) r.state_phi.push_back(state.motion.phi[i]);
        } else if (Is(channel, TopicTraits<msg::DeviceDescription>::kTopic)) {
          if (r.device) return;
          msg::DeviceDescription message;
          DeviceDescription device;
          if (!DecodeRaw(m.data, &message)) return reject(channel.topic, "does not decode");
          if (const std::string why = ReadDevice(message, &device); !why.empty()) return reject(channel.topic, why);
          const int controls = ScenarioControlCount(device.stages);
          if (r.controls > 0 && r.controls != controls) {
            return reject(channel.topic, fmt::format("{} controls, the states before it {}", controls, r.controls));
          }
          r.controls = controls;
          r.device = std::move(device);
        } else if (Is(channel, TopicTraits<msg::Target>::kTopic)) {
          msg::Target message;
          BenchTarget target;
          if (!DecodeRaw(m.data, &message)) return reject(channel.topic, "does not decode");
          if (const std::string why = ReadTarget(message, &target); !why.empty()) return reject(channel.topic, why);
          if (r.targets.empty() || r.targets.back().target.revision != target.revision) {
            r.targets.push_back({m.log_time_ns, std::move(target)});
          }
        }
      });
  r.complete = read.complete;
  r.problem = read.problem;
  for (const record::McapMetadata& metadata : read.metadata) r.metadata[metadata.name] = metadata.values;
  return r;
}

}  // namespace dpc::bus
