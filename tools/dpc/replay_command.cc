#include "replay_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <utility>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/topics.h"
#include "dpc/record/mcap.h"
#include "dpc/cli/command_line.h"

namespace dpc::tools {
namespace {

using Clock = std::chrono::steady_clock;

/// The file's messages are in the order the recorder drained its readers, which may differ from
/// their log times by a drain period: the replay puts them back in log-time order within this.
constexpr uint64_t kReorderWindowNs = 1'000'000'000;
/// At most this many writers (one per topic and partition; commands have one per controller).
constexpr size_t kMaxWriters = 256;

struct StopReplay {};

class Replayer {
 public:
  Replayer(const ReplayOptions& o, bus::BusParticipant* participant) : o_(o), participant_(participant) {}

  /// One pass over the file; false if a stop signal ended it.
  bool Pass(double duration_s) {
    base_.reset();
    try {
      const auto read = record::ReadMcapInLogTimeOrder(
          o_.input_path, kReorderWindowNs, [&](const record::McapChannel& channel, const record::McapMessage& m) {
            if (Wanted(channel.topic)) Publish(channel.topic, m, duration_s);
          });
      if (!read.complete && !warned_cut_) {
        warned_cut_ = true;
        fmt::print(stderr, "dpc replay: {} is not complete ({}); replayed what is before that\n", o_.input_path,
                   read.problem);
      }
    } catch (const StopReplay&) {
      return false;
    }
    return true;
  }

  /// The writers of the file's first seconds created at once, then up to 0.5 s for their readers
  /// to be matched: the timed replay then starts with everyone listening.
  void Prepare() {
    std::optional<uint64_t> first_ns;
    try {
      record::ReadMcap(o_.input_path, [&](const record::McapChannel& channel, const record::McapMessage& m) {
        if (!first_ns) first_ns = m.log_time_ns;
        if (m.log_time_ns > *first_ns + 2'000'000'000) throw StopReplay{};
        bool created = false;
        if (Wanted(channel.topic)) WriterFor(channel.topic, m.data, &created);
      });
    } catch (const StopReplay&) {
    }
    AwaitReaders(std::chrono::milliseconds(500));
    skipped_ = 0;  // counted again when they are published
  }

  void PrintTotals() const {
    std::vector<std::string> counts;
    for (const auto& [topic, count] : per_topic_) counts.push_back(fmt::format("{} {}", topic, count));
    fmt::print(stderr, "dpc replay: {} messages published{}{}\n", published_, counts.empty() ? "" : ": ",
               fmt::join(counts, ", "));
    if (skipped_ > 0) {
      fmt::print(stderr, "dpc replay: {} messages not published ({})\n", skipped_, last_skip_reason_);
    }
  }

 private:
  bool Wanted(const std::string& topic) const {
    if (!ResolveTopic(topic) || ResolveTopic(topic)->name != topic) return false;  // not a bench topic
    if (o_.topics.empty()) return true;
    return std::any_of(o_.topics.begin(), o_.topics.end(),
                       [&](const std::string& t) { return ResolveTopic(t) && ResolveTopic(t)->name == topic; });
  }

  void Skip(std::string reason) {
    ++skipped_;
    last_skip_reason_ = std::move(reason);
  }

  /// The writer of this message's topic and partition (created if new: `*created`); nullptr if
  /// the message does not decode or there are too many writers (counted as skipped).
  bus::Writer<bus::RawSample>* WriterFor(const std::string& topic, const std::string& data, bool* created) {
    return WithTopicMessage(topic, [&](auto tag) -> bus::Writer<bus::RawSample>* {
      using Message = typename decltype(tag)::type;
      Message message;
      if (!bus::DecodeRaw(data, &message)) {
        Skip(fmt::format("a {} message does not decode with its type", topic));
        return nullptr;
      }
      const std::string bench = message.bench_id().to_string();
      std::string controller;
      if constexpr (std::is_same_v<Message, msg::WaveplateCommand>) controller = message.controller_id().to_string();
      const auto key = std::make_pair(topic, bus::PartitionFor<Message>(bench, controller));
      auto writer = writers_.find(key);
      if (writer != writers_.end()) return writer->second.get();
      if (writers_.size() >= kMaxWriters) {
        Skip(fmt::format("more than {} topic/partition pairs", kMaxWriters));
        return nullptr;
      }
      *created = true;
      return writers_.emplace(key, participant_->MakeRawWriter<Message>(bench, controller)).first->second.get();
    });
  }

  /// Up to `timeout` until every writer has a matched reader.
  void AwaitReaders(std::chrono::milliseconds timeout) {
    const auto until = Clock::now() + timeout;
    const auto unmatched = [&] {
      return std::any_of(writers_.begin(), writers_.end(), [](const auto& w) { return w.second->matched_readers() == 0; });
    };
    while (unmatched() && Clock::now() < until) {
      if (StopSignals::requested()) throw StopReplay{};
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  /// Waits until `p` is due (its log time after the first, scaled), then publishes it.
  void Publish(const std::string& topic, const record::McapMessage& p, double duration_s) {
    if (!base_) base_ = std::make_pair(Clock::now(), p.log_time_ns);
    if (o_.rate > 0) {
      const double offset_s = static_cast<double>(p.log_time_ns - std::min(p.log_time_ns, base_->second)) / 1e9 / o_.rate;
      const auto due = base_->first + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset_s));
      for (;;) {
        if (StopSignals::requested()) throw StopReplay{};
        const auto now = Clock::now();
        if (now >= due) break;
        std::this_thread::sleep_for(std::min<Clock::duration>(due - now, std::chrono::milliseconds(50)));
      }
    } else if (StopSignals::requested()) {
      throw StopReplay{};
    }
    bool created = false;
    bus::Writer<bus::RawSample>* writer = WriterFor(topic, p.data, &created);
    if (writer == nullptr) return;
    if (created) {
      // A writer the first seconds did not announce: its first messages would reach no one yet.
      // Give discovery a moment with the replay's clock paused (the timing after it stays the
      // recording's).
      const auto waited_from = Clock::now();
      AwaitReaders(std::chrono::milliseconds(250));
      base_->first += Clock::now() - waited_from;
    }
    if (!writer->Write(bus::RawSample{p.data, 0, 0})) {
      Skip(fmt::format("Fast DDS refused a {} message", topic));
      return;
    }
    ++published_;
    ++per_topic_[topic];
    const auto now = Clock::now();
    if (now >= next_status_) {
      next_status_ = now + std::chrono::seconds(1);
      const double at_s = static_cast<double>(p.log_time_ns - std::min(p.log_time_ns, base_->second)) / 1e9;
      fmt::print(stderr, "dpc replay: at {:.1f} s{} of the recording, {} messages published so far\n", at_s,
                 duration_s > 0 ? fmt::format(" of {:.1f} s", duration_s) : "", published_);
    }
  }

  const ReplayOptions& o_;
  bus::BusParticipant* participant_;
  std::optional<std::pair<Clock::time_point, uint64_t>> base_;  ///< wall and log time of the first message
  std::map<std::pair<std::string, std::string>, std::unique_ptr<bus::Writer<bus::RawSample>>> writers_;
  std::map<std::string, uint64_t> per_topic_;
  uint64_t published_ = 0, skipped_ = 0;
  std::string last_skip_reason_;
  bool warned_cut_ = false;
  Clock::time_point next_status_ = Clock::now() + std::chrono::seconds(1);
};

}  // namespace

CLI::App* AddReplayCommand(CLI::App& app, ReplayOptions* o) {
  CLI::App* replay = app.add_subcommand(
      "replay", "Re-publish a recording (dpc record's MCAP file) with its original timing, into a domain without a bench");
  AddBusToolOptions(*replay, &o->bus, nullptr);
  replay->add_option("file", o->input_path, "The recording (.mcap)")->required()->check(CLI::ExistingFile);
  replay->add_option("--rate", o->rate, "Time scale: 2 plays twice as fast, 0.5 half as fast, 0 as fast as possible")
      ->check(cli::NumberIn(0.0, 1000.0))
      ->capture_default_str();
  replay->add_flag("--loop", o->loop, "Start again at the end, until Ctrl-C");
  replay->add_option("--topics", o->topics,
                     "Only these topics, comma-separated (names or aliases; default: every bench topic recorded)")
      ->delimiter(',');
  replay->add_option("--discovery-wait-s", o->discovery_wait_s,
                     "How long to look for a running bench in the domain before publishing")
      ->check(cli::NumberIn(0.0, 60.0))
      ->capture_default_str();
  return replay;
}

cli::ExitCode RunReplayCommand(const ReplayOptions& o) {
  for (const std::string& name : o.topics) {
    if (!ResolveTopic(name)) {
      fmt::print(stderr, "dpc replay: --topics: unknown topic '{}'; valid: {}\n", name, DescribeValidTopics());
      return cli::ExitCode::kInvalidInput;
    }
  }
  double duration_s = 0.0;
  try {
    // The summary (when the file has one) gives the duration for the status line; a cut file
    // has none and is replayed up to its cut.
    if (const auto summary = record::ReadMcapSummary(o.input_path)) {
      if (summary->message_end_time > summary->message_start_time) {
        duration_s = static_cast<double>(summary->message_end_time - summary->message_start_time) / 1e9;
      }
    }
    record::ReadMcap(o.input_path, [](const record::McapChannel&, const record::McapMessage&) { throw StopReplay{}; });
  } catch (const StopReplay&) {
    // it is MCAP and has a message
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc replay: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }

  StopSignals signals;
  try {
    bus::BusParticipant participant(o.bus.Participant("dpc replay", "observer"));
    {
      // A bench in this domain (any bench id): its samples' or states' writers.
      auto samples = participant.MakeRawReader<msg::StokesSample>("");
      auto states = participant.MakeRawReader<msg::WaveplateState>("");
      const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.discovery_wait_s));
      while (Clock::now() < until && samples->counters().matched_writers == 0 && states->counters().matched_writers == 0) {
        if (StopSignals::requested()) return cli::ExitCode::kOk;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      if (samples->counters().matched_writers > 0 || states->counters().matched_writers > 0) {
        fmt::print(stderr,
                   "dpc replay: domain {} has a running bench (a writer of {}): a replay beside it would reach its "
                   "controllers and driver; replay into a domain of its own (--domain)\n",
                   o.bus.domain_id, samples->counters().matched_writers > 0 ? "samples" : "states");
        return cli::ExitCode::kInvalidInput;
      }
    }
    fmt::print(stderr, "dpc replay: {} into domain {}{}{}\n", o.input_path, o.bus.domain_id,
               o.rate > 0 ? fmt::format(" at {:g}× its speed", o.rate) : " as fast as possible",
               o.loop ? ", in a loop (Ctrl-C to stop)" : "");
    Replayer replayer(o, &participant);
    try {
      replayer.Prepare();
    } catch (const StopReplay&) {
      return cli::ExitCode::kOk;
    }
    while (replayer.Pass(duration_s) && o.loop) {
    }
    replayer.PrintTotals();
    return cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc replay: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
