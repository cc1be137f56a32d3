#include "record_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/topics.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/scenario_loading.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/msg/bench_idl.h"
#include "dpc/record/mcap.h"
#include "dpc/scenario_io/scenario_writer.h"

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

uint64_t WallNs() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<uint64_t>(t.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(t.tv_nsec);
}

/// A message decoded from its raw payload with the real type support; nullopt if it does not
/// decode (then it is recorded anyway, as it arrived).
template <typename Message>
std::optional<Message> Decode(const std::string& bytes) {
  Message message;
  if (!bus::DecodeRaw(bytes, &message)) return std::nullopt;
  return message;
}

/// The polarimeter's sequence numbers as the recording sees them: samples missing between two
/// recorded ones (lost on the way or by the recorder), and restarts (a number not above the last).
struct SampleAccounting {
  uint64_t samples = 0, missing = 0, restarts = 0, undecodable = 0;
  uint64_t last = 0;

  void Count(const std::string& bytes) {
    const auto sample = Decode<msg::StokesSample>(bytes);
    if (!sample) {
      ++undecodable;
      return;
    }
    ++samples;
    const uint64_t n = sample->sequence_number();
    if (samples > 1) {
      if (n > last) {
        missing += n - last - 1;
      } else {
        ++restarts;
      }
    }
    last = n;
  }
};

std::string StatusLine(double elapsed_s, const record::McapWriter& writer, const SampleAccounting& samples,
                       uint64_t lost) {
  return fmt::format("dpc record: {:.0f} s, {} messages ({:.1f} MB), samples {} missing {}{}", elapsed_s,
                     writer.messages(), static_cast<double>(writer.bytes()) / 1e6, samples.samples, samples.missing,
                     lost > 0 ? fmt::format(", {} messages reported lost by DDS", lost) : "");
}

}  // namespace

CLI::App* AddRecordCommand(CLI::App& app, RecordOptions* o) {
  CLI::App* record = app.add_subcommand(
      "record", "Record a bench's topics into an MCAP file (each payload as it arrived, the IDL as its schema)");
  AddBusToolOptions(*record, &o->bus, "The bench to record");
  record->add_option("-o,--output", o->output_path, "The MCAP file to write (replaced if it exists)")->required();
  record->add_option("--topics", o->topics,
                     "Only these topics, comma-separated (names or aliases as `dpc topic list` shows; "
                     "default or all: every bench topic)")
      ->delimiter(',');
  record->add_option("--duration-s", o->duration_s, "Stop after this long (0: until Ctrl-C / SIGTERM)")
      ->check(cli::NonNegativeNumber());
  record->add_option("--compression", o->compression, "Chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}))
      ->capture_default_str();
  record->add_option("--scenario", o->scenario_path,
                     "The bench's scenario file, kept in the recording (metadata \"scenario\")");
  record->add_option("--flush-interval-s", o->flush_interval_s,
                     "Write the chunk being filled at least this often: what a crash can lose at most")
      ->check(cli::NumberIn(0.05, 3600.0))
      ->capture_default_str();
  record->add_option("--udp-receive-buffer-mib", o->udp_receive_buffer_mib,
                     "The UDP receive buffer to ask for: what arrives while the recorder is not scheduled waits "
                     "there instead of being lost (the kernel caps it at net.core.rmem_max; 0: the profile's)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  AddStuckExitOption(*record, &o->stuck_exit_s, ": the file keeps what was flushed, and a supervisor can start a new one");
  return record;
}

cli::ExitCode RunRecordCommand(const RecordOptions& o) {
  // Every check that can refuse the command line comes before the file is created.
  std::vector<BusTopic> topics;
  if (o.topics.empty() || o.topics == std::vector<std::string>{"all"}) {
    topics = BenchTopics();
  } else {
    for (const std::string& name : o.topics) {
      const auto topic = ResolveTopic(name);
      if (!topic) {
        fmt::print(stderr, "dpc record: --topics: unknown topic '{}'; valid: {}\n", name, DescribeValidTopics());
        return cli::ExitCode::kInvalidInput;
      }
      if (std::none_of(topics.begin(), topics.end(), [&](const BusTopic& t) { return t.name == topic->name; })) {
        topics.push_back(*topic);
      }
    }
  }
  std::string scenario_text;
  if (!o.scenario_path.empty()) {
    try {
      const ScenarioConfig scenario = cli::LoadScenarioWithOverrides(o.scenario_path, {}, PaperScenario("131"));
      ValidateScenario(scenario);
      scenario_text = ScenarioToText(scenario);
    } catch (const ScenarioError& e) {
      fmt::print(stderr, "dpc record: --scenario {}: {}\n", o.scenario_path, cli::DescribeScenarioError(e, {}));
      return cli::ExitCode::kInvalidInput;
    }
  }

  StopSignals signals;
  // Made first: it also guards the end (the file closed, the participant deleted).
  const std::unique_ptr<cli::LoopGuard> guarded =
      GuardCommandLoop("record", o.stuck_exit_s, "; " + o.output_path + " keeps what was flushed (dpc info reads it)");
  cli::LoopGuard& guard = *guarded;
  guard.Phase("its drains");
  try {
    record::McapWriter writer(o.output_path, {cli::VersionText("dpc record"),
                                              record::ParseMcapCompression(o.compression), 1 << 20});
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    BusToolOptions bus_options = o.bus;
    bus_options.udp_receive_buffer_bytes = static_cast<uint32_t>(o.udp_receive_buffer_mib) << 20;
    const uint64_t kernel_limit_bytes = bus::KernelUdpReceiveBufferLimitBytes();
    record::McapMetadata recorder{"recorder",
                                  {{"version", cli::VersionText("dpc")},
                                   {"host", host},
                                   {"domain", std::to_string(o.bus.domain_id)},
                                   {"bench_id", o.bus.bench_id},
                                   {"start_time_ns", std::to_string(WallNs())}}};
    if (bus_options.udp_receive_buffer_bytes > 0) {
      // What the kernel grants (it caps the request silently): a reader of the file can tell
      // whether a loss may have been the recorder's.
      recorder.values["udp_receive_buffer_bytes"] =
          std::to_string(bus::GrantedUdpReceiveBufferBytes(bus_options.udp_receive_buffer_bytes, kernel_limit_bytes));
    }
    writer.WriteMetadata(recorder);
    if (!scenario_text.empty()) writer.WriteMetadata({"scenario", {{"path", o.scenario_path}, {"text", scenario_text}}});

    ObserverParticipant participant(bus_options, "dpc record", "observer");
    participant.SetPhaseReport([&guard](const char* phase) { return guard.Phase(phase); });
    struct Channel {
      uint16_t id = 0;
      uint32_t sequence = 0;  ///< of the messages kept
      std::string topic;
      std::unique_ptr<bus::RawReader> reader;
    };
    std::vector<Channel> channels;
    uint16_t sample_channel = UINT16_MAX, device_channel = UINT16_MAX;
    const std::string idl(msg::BenchIdlText());
    for (const BusTopic& topic : topics) {
      WithTopicMessage(topic.name, [&](auto tag) {
        using Message = typename decltype(tag)::type;
        const uint16_t schema = writer.AddSchema(std::string(topic.type_name), "omgidl", idl);
        const uint16_t channel = writer.AddChannel(schema, std::string(topic.name), "cdr",
                                                   {{"partition", bus::PartitionFor<Message>(o.bus.bench_id)}});
        if constexpr (std::is_same_v<Message, msg::StokesSample>) sample_channel = channel;
        if constexpr (std::is_same_v<Message, msg::DeviceDescription>) device_channel = channel;
        channels.push_back({channel, 0, std::string(topic.name), nullptr});
      });
    }
    // The readers, on the participant there is (again, after it healed a stalled handshake).
    const auto make_readers = [&] {
      for (Channel& channel : channels) {
        WithTopicMessage(channel.topic, [&](auto tag) {
          channel.reader = participant->MakeRawReader<typename decltype(tag)::type>(o.bus.bench_id);
        });
      }
    };
    make_readers();
    fmt::print(stderr, "dpc record: {} topic{} of bench {} (domain {}) → {}{}\n", channels.size(),
               channels.size() == 1 ? "" : "s", o.bus.bench_id, o.bus.domain_id, o.output_path,
               o.duration_s > 0 ? fmt::format(" for {:g} s", o.duration_s) : ", Ctrl-C to stop");
    if (bus_options.udp_receive_buffer_bytes > 0) {
      fmt::print(stderr, "dpc record: {}\n",
                 bus::UdpReceiveBufferNote(bus_options.udp_receive_buffer_bytes, kernel_limit_bytes));
    }

    SampleAccounting samples;
    std::string last_device;  // the device description's payload last kept as metadata
    uint64_t lost = 0;        // messages Fast DDS reported lost (sent, never taken), over every topic
    uint64_t lost_before = 0;  // of the readers a heal deleted
    std::vector<bus::RawSample> taken;
    // Drains every reader into the file: each message with log time = its reception, publish
    // time = its writer's source timestamp.
    const auto drain = [&] {
      lost = lost_before;
      for (Channel& channel : channels) {
        taken.clear();
        channel.reader->TakeAll(&taken);
        lost += channel.reader->lost();
        for (bus::RawSample& raw : taken) {
          const uint64_t log_time_ns = raw.reception_time_ns != 0 ? raw.reception_time_ns : WallNs();
          if (channel.id == sample_channel) samples.Count(raw.bytes);
          if (channel.id == device_channel && raw.bytes != last_device) {
            last_device = raw.bytes;
            if (const auto device = Decode<msg::DeviceDescription>(raw.bytes)) {
              writer.WriteMetadata(
                  {"device_description",
                   {{"json", ToJson(*device).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)},
                    {"log_time_ns", std::to_string(log_time_ns)}}});
            }
          }
          writer.Write({channel.id, ++channel.sequence, log_time_ns, raw.source_time_ns, std::move(raw.bytes)});
        }
      }
    };

    const bool on_terminal = isatty(STDERR_FILENO) == 1;
    const auto start = Clock::now();
    const auto flush_interval = std::chrono::duration<double>(o.flush_interval_s);
    auto next_status = start + std::chrono::seconds(1);
    auto next_flush = start + std::chrono::duration_cast<Clock::duration>(flush_interval);
    for (;;) {
      guard.Turn();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      drain();
      const bool healed = participant.Heal(
          [&] {
            drain();  // what the old readers hold is kept
            lost_before = lost;
            for (Channel& channel : channels) channel.reader.reset();
          },
          make_readers);
      if (healed) {
        // The gap it leaves shows in the samples' accounting; the file says when it was.
        writer.WriteMetadata({"participant_reload",
                              {{"cause", "handshake stall"}, {"log_time_ns", std::to_string(WallNs())}}});
      }
      const auto now = Clock::now();
      const double elapsed_s = std::chrono::duration<double>(now - start).count();
      const bool done = StopSignals::requested() || (o.duration_s > 0 && elapsed_s >= o.duration_s);
      if (now >= next_flush) {
        writer.Flush();
        next_flush = now + std::chrono::duration_cast<Clock::duration>(flush_interval);
      }
      if (now >= next_status && !done) {
        next_status = now + std::chrono::seconds(1);
        // On a terminal one line redrawn in place; in a log one line per second.
        if (on_terminal) {
          fmt::print(stderr, "\r\x1b[K{}", StatusLine(elapsed_s, writer, samples, lost));
        } else {
          fmt::print(stderr, "{}\n", StatusLine(elapsed_s, writer, samples, lost));
        }
      }
      if (done) break;
    }
    guard.Phase("closing the file and deleting its DDS entities");
    guard.Stopping();
    if (on_terminal) fmt::print(stderr, "\r\x1b[K");
    drain();
    writer.WriteMetadata({"recording",
                          {{"end_time_ns", std::to_string(WallNs())},
                           {"samples", std::to_string(samples.samples)},
                           {"samples_missing", std::to_string(samples.missing)},
                           {"sample_restarts", std::to_string(samples.restarts)},
                           {"lost_reported_by_dds", std::to_string(lost)},
                           {"participant_reloads", std::to_string(participant.reloads())}}});
    writer.Close();
    fmt::print(stderr, "dpc record: {} messages in {} chunks, {:.1f} MB → {}\n", writer.messages(), writer.chunks(),
               static_cast<double>(writer.bytes()) / 1e6, o.output_path);
    fmt::print(stderr, "dpc record: samples {} (sequence numbers missing between them: {}, restarts: {}){}\n",
               samples.samples, samples.missing, samples.restarts,
               lost > 0 ? fmt::format("; {} messages of any topic reported lost by DDS (sent, never received)", lost)
                        : "");
    return cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc record: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
