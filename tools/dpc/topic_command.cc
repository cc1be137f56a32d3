#include "topic_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using Clock = std::chrono::steady_clock;

template <typename T>
std::string ToString(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

bool PrintLine(const std::string& line) {
  std::fputs(line.c_str(), stdout);
  std::fputc('\n', stdout);
  return std::fflush(stdout) == 0;
}

// ---- list

/// Remote endpoints and participants, as discovery reports them (Fast DDS's listener thread).
class DiscoveryListener final : public fdds::DomainParticipantListener {
 public:
  struct Endpoint {
    std::string topic;
    std::string type;
    std::string participant;  ///< GUID prefix
    bool writer;
  };

  void on_participant_discovery(fdds::DomainParticipant*, rtps::ParticipantDiscoveryInfo&& info) override {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string prefix = ToString(info.info.m_guid.guidPrefix);
    switch (info.status) {
      case rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT:
      case rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT:
        participants_[prefix] = info.info.m_participantName.to_string();
        break;
      default:  // removed, dropped (lease expired), ignored
        participants_.erase(prefix);
        std::erase_if(endpoints_, [&](const auto& e) { return e.second.participant == prefix; });
        break;
    }
  }
  void on_publisher_discovery(fdds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    Update(ToString(info.info.guid()), info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER,
           {info.info.topicName().to_string(), info.info.typeName().to_string(),
            ToString(info.info.guid().guidPrefix), true});
  }
  void on_subscriber_discovery(fdds::DomainParticipant*, rtps::ReaderDiscoveryInfo&& info) override {
    Update(ToString(info.info.guid()), info.status == rtps::ReaderDiscoveryInfo::REMOVED_READER,
           {info.info.topicName().to_string(), info.info.typeName().to_string(),
            ToString(info.info.guid().guidPrefix), false});
  }

  std::map<std::string, Endpoint> endpoints() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return endpoints_;
  }
  std::map<std::string, std::string> participants() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return participants_;
  }

 private:
  void Update(const std::string& guid, bool removed, Endpoint endpoint) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (removed) {
      endpoints_.erase(guid);
    } else {
      endpoints_[guid] = std::move(endpoint);
    }
  }

  mutable std::mutex mutex_;
  std::map<std::string, Endpoint> endpoints_;        ///< by GUID
  std::map<std::string, std::string> participants_;  ///< GUID prefix → name
};

// ---- echo

template <typename Message>
cli::ExitCode RunEchoOf(const TopicEchoOptions& o, const BusTopic& topic) {
  std::mutex mutex;
  std::condition_variable arrived;
  std::deque<std::string> lines;
  int64_t accepted = 0;
  ObserverParticipant participant(o.bus, "dpc topic echo", "observer");
  std::unique_ptr<bus::Reader<Message>> reader;
  // On the participant there is (again, after it healed a stalled handshake).
  const auto make_reader = [&] {
    reader = participant->MakeReader<Message>(
        BenchFilter(o.bus.bench_id), [&](const Message& message, const fdds::SampleInfo&) {
          std::string line = o.json ? ToJson(message).dump(-1, ' ', false,
                                                           nlohmann::json::error_handler_t::replace)
                                    : ToText(message);
          std::lock_guard<std::mutex> lock(mutex);
          if (o.count > 0 && accepted >= o.count) return;
          ++accepted;
          lines.push_back(std::move(line));
          arrived.notify_one();
        });
  };
  make_reader();
  const auto start = Clock::now();
  int64_t printed = 0;
  bool output_ok = true;
  while (output_ok) {
    std::deque<std::string> batch;
    {
      std::unique_lock<std::mutex> lock(mutex);
      arrived.wait_for(lock, std::chrono::milliseconds(20), [&] { return !lines.empty(); });
      batch.swap(lines);
    }
    for (const std::string& line : batch) {
      if (!PrintLine(line)) {
        output_ok = false;
        break;
      }
      ++printed;
    }
    if (o.count > 0 && printed >= o.count) break;
    if (StopSignals::requested()) break;
    participant.Heal([&] { reader.reset(); }, make_reader);
    if (o.timeout_s > 0 && SecondsSince(start) >= o.timeout_s) {
      if (printed == 0) {
        reader.reset();
        fmt::print(stderr,
                   "dpc topic echo: no sample on {} (domain {}, bench {}) within {:g} s (is the "
                   "bench running on this domain and bench id?)\n",
                   topic.name, o.bus.domain_id, o.bus.bench_id.empty() ? "*" : o.bus.bench_id,
                   o.timeout_s);
        return cli::ExitCode::kNoData;
      }
      if (o.count > 0) {
        fmt::print(stderr, "dpc topic echo: {} of {} samples within {:g} s\n", printed, o.count,
                   o.timeout_s);
      }
      break;
    }
  }
  return output_ok ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
}

// ---- hz

struct WindowStats {
  int64_t samples = 0;
  double min_s = 0, sum_s = 0, max_s = 0;
};

template <typename Message>
cli::ExitCode RunHzOf(const TopicHzOptions& o, const BusTopic& topic) {
  std::mutex mutex;
  std::vector<Clock::time_point> arrivals;
  arrivals.reserve(1 << 16);
  ObserverParticipant participant(o.bus, "dpc topic hz", "observer");
  std::unique_ptr<bus::Reader<Message>> reader;
  // On the participant there is (again, after it healed a stalled handshake).
  const auto make_reader = [&] {
    reader = participant->MakeReader<Message>(BenchFilter(o.bus.bench_id), [&](const Message&, const fdds::SampleInfo&) {
      const auto now = Clock::now();
      std::lock_guard<std::mutex> lock(mutex);
      arrivals.push_back(now);
    });
  };
  make_reader();
  const auto heal = [&] { participant.Heal([&] { reader.reset(); }, make_reader); };
  const auto has_sample = [&] {
    heal();
    std::lock_guard<std::mutex> lock(mutex);
    return !arrivals.empty();
  };
  if (!WaitFor(has_sample, o.timeout_s)) {
    if (StopSignals::requested()) return cli::ExitCode::kOk;
    fmt::print(stderr, "dpc topic hz: no sample on {} (domain {}, bench {}) within {:g} s\n",
               topic.name, o.bus.domain_id, o.bus.bench_id.empty() ? "*" : o.bus.bench_id,
               o.timeout_s);
    return cli::ExitCode::kNoData;
  }
  Clock::time_point last;
  {
    std::lock_guard<std::mutex> lock(mutex);
    last = arrivals.front();
    arrivals.erase(arrivals.begin());
  }
  const auto window = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.window_s));
  Clock::time_point window_end = last;
  std::vector<Clock::time_point> taken;
  for (int64_t w = 0; o.count_windows == 0 || w < o.count_windows; ++w) {
    window_end += window;
    while (Clock::now() < window_end && !StopSignals::requested()) {
      std::this_thread::sleep_for(std::min<Clock::duration>(window_end - Clock::now(),
                                                           std::chrono::milliseconds(20)));
      heal();
    }
    if (StopSignals::requested()) break;
    {
      std::lock_guard<std::mutex> lock(mutex);
      taken.swap(arrivals);
      arrivals.clear();
      // Arrivals after the window's end belong to the next one.
      const auto split = std::partition_point(taken.begin(), taken.end(),
                                              [&](Clock::time_point t) { return t <= window_end; });
      arrivals.assign(split, taken.end());
      taken.erase(split, taken.end());
    }
    WindowStats stats;
    for (Clock::time_point t : taken) {
      const double dt = std::chrono::duration<double>(t - last).count();
      last = t;
      stats.min_s = stats.samples == 0 ? dt : std::min(stats.min_s, dt);
      stats.max_s = stats.samples == 0 ? dt : std::max(stats.max_s, dt);
      stats.sum_s += dt;
      ++stats.samples;
    }
    const double rate_hz = static_cast<double>(stats.samples) / o.window_s;
    std::string line;
    if (o.json) {
      nlohmann::ordered_json j{{"topic", std::string(topic.name)},
                               {"window_s", o.window_s},
                               {"samples", stats.samples},
                               {"rate_hz", rate_hz}};
      if (stats.samples > 0) {
        j["interval_ms"] = {{"min", stats.min_s * 1e3},
                            {"mean", stats.sum_s / stats.samples * 1e3},
                            {"max", stats.max_s * 1e3}};
      } else {
        j["interval_ms"] = nullptr;
      }
      line = j.dump();
    } else if (stats.samples > 0) {
      line = fmt::format("{}: rate_hz={:.1f} samples={} window_s={:g} interval_ms min={:.3f} "
                         "mean={:.3f} max={:.3f}",
                         topic.name, rate_hz, stats.samples, o.window_s, stats.min_s * 1e3,
                         stats.sum_s / stats.samples * 1e3, stats.max_s * 1e3);
    } else {
      line = fmt::format("{}: rate_hz=0.0 samples=0 window_s={:g} (no samples)", topic.name,
                         o.window_s);
    }
    if (!PrintLine(line)) return cli::ExitCode::kRuntimeError;
  }
  return cli::ExitCode::kOk;
}

std::optional<BusTopic> ResolveOrExplain(const std::string& name, const char* command) {
  auto topic = ResolveTopic(name);
  if (!topic) {
    fmt::print(stderr, "dpc topic {}: unknown topic \"{}\"; the bench's topics are: {}\n", command,
               name, DescribeValidTopics());
  }
  return topic;
}

template <typename Body>
cli::ExitCode GuardBusErrors(const char* command, Body&& body) {
  try {
    return body();
  } catch (const bus::BusError& e) {
    fmt::print(stderr, "dpc topic {}: {}\n", command, e.what());
    return cli::ExitCode::kInitializationError;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc topic {}: {}\n", command, e.what());
  }
  return cli::ExitCode::kRuntimeError;
}

}  // namespace

CLI::App* AddTopicCommand(CLI::App& app, TopicOptions* o) {
  CLI::App* topic = app.add_subcommand("topic", "Inspect the bench's DDS topics (list, echo, hz)");
  topic->require_subcommand(1);

  CLI::App* list = topic->add_subcommand(
      "list", "Discover the topics on a domain: name, type, number of writers and readers");
  AddBusToolOptions(*list, &o->list.bus, nullptr);
  list->add_option("--wait-s", o->list.wait_s, "How long to listen to discovery")
      ->check(cli::NumberIn(0.05, 600.0))
      ->capture_default_str();
  o->list_command = list;

  const char* bench_help = "Only this bench's samples (\"*\" or \"\": all benches)";
  const std::string topic_help = "Topic: " + DescribeValidTopics();
  CLI::App* echo = topic->add_subcommand("echo", "Print every sample of one of the bench's topics");
  echo->add_option("topic", o->echo.topic, topic_help)->required();
  AddBusToolOptions(*echo, &o->echo.bus, bench_help);
  echo->add_flag("--json", o->echo.json, "One JSON object per line with every field of the IDL type");
  echo->add_option("--count", o->echo.count, "Exit 0 after this many samples (0: until stopped)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  echo->add_option("--timeout-s", o->echo.timeout_s,
                   "Stop after this long; exit 3 if nothing arrived (0: no timeout)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  o->echo_command = echo;

  CLI::App* hz = topic->add_subcommand(
      "hz", "Measure the arrival rate and inter-arrival times of one of the bench's topics");
  hz->add_option("topic", o->hz.topic, topic_help)->required();
  AddBusToolOptions(*hz, &o->hz.bus, bench_help);
  hz->add_option("--window-s", o->hz.window_s, "Length of a measurement window")
      ->check(cli::NumberIn(0.01, 3600.0))
      ->capture_default_str();
  hz->add_option("--count-windows", o->hz.count_windows, "Exit 0 after this many windows (0: until stopped)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  hz->add_option("--timeout-s", o->hz.timeout_s,
                 "Exit 3 if no sample arrives within this long (0: wait forever)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  hz->add_flag("--json", o->hz.json, "One JSON object per window");
  o->hz_command = hz;
  return topic;
}

cli::ExitCode RunTopicCommand(const TopicOptions& o) {
  if (o.list_command != nullptr && o.list_command->parsed()) return RunTopicList(o.list);
  if (o.echo_command != nullptr && o.echo_command->parsed()) return RunTopicEcho(o.echo);
  if (o.hz_command != nullptr && o.hz_command->parsed()) return RunTopicHz(o.hz);
  return cli::ExitCode::kInvalidInput;
}

cli::ExitCode RunTopicList(const TopicListOptions& o) {
  StopSignals signals;
  return GuardBusErrors("list", [&]() -> cli::ExitCode {
    // Our own participant (not bus::BusParticipant) so that the listener is there from the
    // start: discovery callbacks begin as soon as the participant exists.
    const std::string profiles = bus::ResolveProfilesFile();
    setenv(bus::kProfilesEnvironmentVariable, profiles.c_str(), 1);
    auto* factory = fdds::DomainParticipantFactory::get_instance();
    if (factory->load_profiles() != ReturnCode_t::RETCODE_OK) {
      throw bus::BusError(fmt::format("{}: Fast DDS could not load this XML profiles file", profiles));
    }
    fdds::DomainParticipantQos qos;
    if (factory->get_participant_qos_from_profile(bus::kParticipantProfile, qos) != ReturnCode_t::RETCODE_OK) {
      throw bus::BusError(fmt::format("{}: no participant profile \"{}\"", profiles, bus::kParticipantProfile));
    }
    qos.name("dpc topic list");
    DiscoveryListener listener;
    fdds::DomainParticipant* participant = factory->create_participant(o.bus.domain_id, qos, &listener);
    if (participant == nullptr) {
      throw bus::BusError(fmt::format("Fast DDS could not create a participant on domain {}", o.bus.domain_id));
    }
    WaitFor([] { return false; }, o.wait_s);
    const auto endpoints = listener.endpoints();
    const auto participants = listener.participants();
    participant->set_listener(nullptr);
    factory->delete_participant(participant);
    if (StopSignals::requested()) return cli::ExitCode::kOk;

    struct Row {
      std::set<std::string> types;
      int writers = 0, readers = 0;
    };
    std::map<std::string, Row> rows;
    for (const auto& [guid, e] : endpoints) {
      Row& row = rows[e.topic];
      row.types.insert(e.type);
      (e.writer ? row.writers : row.readers) += 1;
    }
    if (rows.empty()) {
      fmt::print(stderr, "dpc topic list: no topics discovered on domain {} within {:g} s\n",
                 o.bus.domain_id, o.wait_s);
      return cli::ExitCode::kOk;
    }
    size_t name_width = 5, type_width = 4;
    for (const auto& [name, row] : rows) {
      name_width = std::max(name_width, name.size());
      const std::string types = fmt::format("{}", fmt::join(row.types, "|"));
      type_width = std::max(type_width, types.size());
    }
    std::string out = fmt::format("{:<{}}  {:<{}}  {:>7}  {:>7}\n", "topic", name_width, "type",
                                  type_width, "writers", "readers");
    for (const auto& [name, row] : rows) {
      const std::string types = fmt::format("{}", fmt::join(row.types, "|"));
      out += fmt::format("{:<{}}  {:<{}}  {:>7}  {:>7}\n", name, name_width, types, type_width,
                         row.writers, row.readers);
    }
    std::vector<std::string> names;
    for (const auto& [prefix, name] : participants) names.push_back(name.empty() ? prefix : name);
    std::sort(names.begin(), names.end());
    out += fmt::format("participants ({}): {}\n", names.size(), fmt::join(names, ", "));
    std::fputs(out.c_str(), stdout);
    return std::fflush(stdout) == 0 ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
  });
}

cli::ExitCode RunTopicEcho(const TopicEchoOptions& o) {
  const auto topic = ResolveOrExplain(o.topic, "echo");
  if (!topic) return cli::ExitCode::kInvalidInput;
  StopSignals signals;
  return GuardBusErrors("echo", [&] {
    return WithTopicMessage(topic->name, [&](auto type) {
      return RunEchoOf<typename decltype(type)::type>(o, *topic);
    });
  });
}

cli::ExitCode RunTopicHz(const TopicHzOptions& o) {
  const auto topic = ResolveOrExplain(o.topic, "hz");
  if (!topic) return cli::ExitCode::kInvalidInput;
  StopSignals signals;
  return GuardBusErrors("hz", [&] {
    return WithTopicMessage(topic->name, [&](auto type) {
      return RunHzOf<typename decltype(type)::type>(o, *topic);
    });
  });
}

}  // namespace dpc::tools
