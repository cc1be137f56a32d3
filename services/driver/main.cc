// dpc-driver: the waveplate driver. Obeys one controller (priority, liveness), validates,
// clamps and slew-limits its commands, applies them to the backend (the simulated device, or a
// real one over a serial port or TCP: the scenario's waveplate_device) and
// publishes the state; owns the device description and the target on the bus.
//
//   dpc-driver [SCENARIO] [--domain N] [--bench-id ID] [--max-slew-per-s X] [--min-silence-s T]

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <condition_variable>
#include <mutex>

#include <spdlog/spdlog.h>

#include "dpc/bench/bench_messages.h"
#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/event_thread_canary.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/participant_maker.h"
#include "dpc/cli/command_line.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "driver_core.h"
#include "line_waveplates.h"
#include "log_limiter.h"
#include "service.h"
#include "target_authority.h"

namespace dpc::services {
namespace {

namespace fdds = eprosima::fastdds::dds;

/// The scenario (validated whole, as `dpc sim` does) and the backend's initial φ.
ScenarioConfig LoadDriverScenario(const CommonOptions& common) {
  ScenarioConfig scenario = LoadServiceScenario(common);
  ValidateScenario(scenario);
  if (const int controls = ScenarioControlCount(scenario.stages); controls > static_cast<int>(msg::MAX_CONTROLS)) {
    throw ConfigurationError(fmt::format("invalid scenario: stages: {} controls, more than the {} a bench command "
                                         "carries (idl/dpc/bench.idl MAX_CONTROLS)",
                                         controls, msg::MAX_CONTROLS));
  }
  return scenario;
}

class DriverService final : public Service {
 public:
  struct Options {
    DriverSettings settings;
    double tick_s = 2.5e-4;
    std::string device_record;  ///< empty: DeviceRecord::DefaultPath; "none": no record
  };

  static void AddOptions(CLI::App& app, Options* o) {
    DriverSettings& s = o->settings;
    app.add_option("--id", s.driver_id, "Driver id")->capture_default_str();
    app.add_option("--max-slew-per-s", s.max_slew_per_s,
                   "Slew-rate limit of every control, φ units per second of the driver's clock (0: "
                   "the device's own limit; a value above it is cut to it)")
        ->check(cli::NonNegativeNumber())->capture_default_str();
    app.add_option("--min-silence-s", s.min_silence_s,
                   "The obeyed controller is dead when another answered a sample it did not and it stayed "
                   "silent this long since (or 1.5 of its command intervals, if longer): fail over. Meanwhile "
                   "the other controller's answers stand in for the samples it owes. "
                   "If nobody answers for this long or --silence-intervals of the command interval "
                   "(no samples, no other controller), hold; the controller obeyed before gets "
                   "control back first")
        ->check(cli::NumberIn(1e-4, 10.0))->capture_default_str();
    app.add_option("--silence-intervals", s.silence_intervals, "Silence timeout in command intervals")
        ->check(cli::NumberIn(2.0, 1000.0))->capture_default_str();
    app.add_option("--max-ramp-s", s.max_ramp_s,
                   "A command's rate (phi_rate_per_s) moves the waveplates for at most this long of "
                   "bench time; the next command normally replaces it long before")
        ->check(cli::NumberIn(0.0, 1.0))->capture_default_str();
    app.add_option("--device-record", o->device_record,
                   "Where the simulated waveplates' position is kept across driver restarts (a file "
                   "mapped in memory; default /dev/shm/dpc-waveplates-<domain>-<bench>-<id>; none: "
                   "start from the scenario's initial φ every time)");
    app.add_option("--tick-s", o->tick_s, "Shortest interval between the driver's checks for silent controllers")
        ->check(cli::NumberIn(1e-5, 0.1))->capture_default_str();
  }
  static std::string LogName(const Options&) { return "driver"; }

  DriverService(const CommonOptions& common, const Options& options)
      : bench_id_(common.bench_id),
        tick_ns_(static_cast<int64_t>(options.tick_s * 1e9)),
        scenario_(LoadDriverScenario(common)),
        record_(scenario_.waveplate_device ? nullptr : MakeRecord(common, options, scenario_)),
        backend_(MakeBackend(scenario_, record_.get())),
        core_(scenario_.stages, WithDeviceRamps(options.settings, *backend_), backend_.get()),
        targets_(scenario_.target, TargetAuthority::EpochNow()),
        device_message_(bus::DeviceMessage(
            DeviceDescription{options.settings.driver_id, scenario_.stages, core_.max_slew_per_s(),
                              WithDeviceRamps(options.settings, *backend_).max_ramp_s},
            bench_id_)),
        maker_({common.domain_id, "dpc-driver/" + common.bench_id,
                {common.security_dir, common.identity.empty() ? "driver" : common.identity}},
               bus::DescribedPeerEvents(PeerLogger()), LogLine),
        participant_(maker_.Make()) {
    targets_revision_ = targets_.current().revision;
    first_target_ns_ = WallClockNs();  // (the source timestamp the other drivers see, near enough)
    started_monotonic_ns_ = MonotonicNs();
    MakeEndpoints();
    for (const std::string& line : bus::DescribeShmCleanup(participant_->shm_cleanup())) spdlog::info("{}", line);
    spdlog::info("{} controls, profiles {}, domain {}", core_.control_count(), participant_->profiles_file(),
                 common.domain_id);
  }

  ~DriverService() override { DeleteEndpoints(); }

  /// A tick waits at most kMaxSleepNs; the waveplates' I/O has a thread of its own.
  std::optional<double> LongestTurnS() const override { return 0.0; }
  cli::Heartbeat GuardHeartbeat() const override {
    return {bus::OldestEventThreadTickNs, bus::kEventThreadStuckS, bus::kEventThreadWhat};
  }

  /// The ticker: wakes when the core's next deadline is due (a stand-in's wait, the obeyed
  /// controller's grace or silence timeout, the holding heartbeat), at most every --tick-s; a
  /// command that brings the deadline forward wakes it (WakeTickerIfSooner), and stop() at once.
  /// A reload (SIGHUP) is done here, between two ticks.
  cli::ExitCode run() override {
    GuardPhase("its ticks");
    maker_.SetPhaseReport([this](const char* phase) { return GuardPhase(phase); });
    constexpr int64_t kMaxSleepNs = 5'000'000;
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stopped()) {
      Turned();
      // A SIGHUP, or a handshake stall: progress is a state that applies a command (holding is
      // none), which a controller or the polarimeter whose handshake with this driver stalled
      // withholds. Secured, the ticks go on on the old participant while the new one
      // authenticates the peers (ParticipantMaker::Reload). Once the endpoints move, the
      // controllers' commands go nowhere until the new endpoints are matched: the waveplates stay
      // where they are; then the usual rules (silence, hold, failover) apply to what arrives.
      if (const auto cause = maker_.ReloadCause(TakeReloadRequest(), *participant_, MonotonicNs(), progress_ns_)) {
        lock.unlock();
        maker_.Reload(&participant_, [this] { DeleteEndpoints(); }, [this] { MakeEndpoints(); }, *cause);
        lock.lock();
      }
      const int64_t now_ns = MonotonicNs();
      core_.SetControllersConnected(commands_->counters().matched_writers.load(std::memory_order_relaxed));
      if (auto state = core_.Tick(now_ns, WallClockNs())) Publish(std::move(*state));
      last_tick_ns_ = now_ns;
      tick_due_ns_ = std::clamp(core_.NextTickNs(), now_ns + tick_ns_, now_ns + kMaxSleepNs);
      while (!stopped() && MonotonicNs() < tick_due_ns_) {
        tick_wake_.wait_until(lock, std::chrono::steady_clock::time_point(std::chrono::nanoseconds(tick_due_ns_)));
      }
    }
    lock.unlock();
    if (const auto* line = dynamic_cast<const LineWaveplates*>(backend_.get())) {
      const LineWaveplates::Counters c = line->counters();
      const auto [p50_us, p99_us] = line->ApplyTimesUs();
      spdlog::info("{}: {} set lines, {} refused replies, {} timeouts, {} connections ({} failed); a command "
                   "acknowledged after p50 {:.0f} µs, p99 {:.0f} µs",
                   line->name(), c.sets, c.refused_replies, c.timeouts, c.connects, c.failed_connects, p50_us, p99_us);
    }
    if (displaced_.load()) {
      spdlog::error("another driver drives bench {}: this one (started later) leaves the waveplates to it",
                    bench_id_);
      return cli::ExitCode::kRuntimeError;
    }
    return cli::ExitCode::kOk;
  }

 private:
  /// Without mutex_ (the readers' callbacks take it): the writers on participant_, and what they
  /// always carry first: the device description, the current target (both TRANSIENT_LOCAL:
  /// every newcomer gets them) and the state; then the readers (their callbacks write).
  void MakeEndpoints() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      state_writer_ = participant_->MakeWriter<msg::WaveplateState>(bench_id_);
      device_writer_ = participant_->MakeWriter<msg::DeviceDescription>(bench_id_);
      target_writer_ = participant_->MakeWriter<msg::Target>(bench_id_);
      reply_writer_ = participant_->MakeWriter<msg::TargetReply>(bench_id_);
      device_writer_->Write(device_message_);
      target_writer_->Write(bus::TargetMessage(targets_.current(), bench_id_));
      Publish(core_.Publishable(WallClockNs()));
    }
    // The driver's own record of the bench's samples: a command is judged by it (SampleTimeline).
    samples_ = participant_->MakeReader<msg::StokesSample>(
        bench_id_, [this](const msg::StokesSample& message, const fdds::SampleInfo& info) { OnSample(message, info); });
    commands_ = participant_->MakeReader<msg::WaveplateCommand>(
        bench_id_, [this](const msg::WaveplateCommand& message, const fdds::SampleInfo& info) {
          OnCommand(message, participant_->WriterPartition(info.sample_identity.writer_guid()));
        });
    // Another driver on this bench: its target (TRANSIENT_LOCAL: a newcomer sees the one already
    // there at once) comes from a writer of another participant. The driver that started
    // later (a larger epoch in its revisions; ties: the larger participant GUID) leaves, but
    // only while it is starting (kYieldWindowNs): a driver that has been driving never leaves
    // on a peer's word, so a forged target claiming an earlier start cannot take the bench's
    // driver away (it is logged as a second driver).
    others_ = participant_->MakeReader<msg::Target>(
        bench_id_, [this](const msg::Target& message, const fdds::SampleInfo& info) { OnTarget(message, info); });
    requests_ = participant_->MakeReader<msg::TargetRequest>(
        bench_id_, [this](const msg::TargetRequest& message, const auto&) { OnTargetRequest(message); });
  }

  /// Without mutex_: the readers first (their callbacks take it and use the core and the
  /// writers; deleting a reader waits for its callback), then the writers.
  void DeleteEndpoints() {
    others_.reset();
    commands_.reset();
    requests_.reset();
    samples_.reset();
    std::lock_guard<std::mutex> lock(mutex_);
    state_writer_.reset();
    device_writer_.reset();
    target_writer_.reset();
    reply_writer_.reset();
  }

  static std::unique_ptr<DeviceRecord> MakeRecord(const CommonOptions& common, const Options& options,
                                                  const ScenarioConfig& scenario) {
    if (options.device_record == "none") return nullptr;
    const std::string path = options.device_record.empty()
                                 ? DeviceRecord::DefaultPath(common.domain_id, common.bench_id, options.settings.driver_id)
                                 : options.device_record;
    try {
      return std::make_unique<DeviceRecord>(path, ScenarioControlCount(scenario.stages));
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(fmt::format("--device-record: {}", e.what()));
    }
  }

  /// The scenario's device: a line-protocol one (waveplate_device), else the simulated one.
  static std::unique_ptr<WaveplateBackend> MakeBackend(const ScenarioConfig& scenario, DeviceRecord* record) {
    if (!scenario.waveplate_device) {
      return std::make_unique<SimulatedWaveplates>(InitialPhi(scenario, record), DeviceLimits{}, record);
    }
    const WaveplateChain chain = BuildChain(scenario.stages);
    std::vector<ControlRange> ranges;
    for (size_t i = 0; i < chain.range_min().size(); ++i) ranges.push_back({chain.range_min()[i], chain.range_max()[i]});
    auto device = std::make_unique<LineWaveplates>(
        *scenario.waveplate_device, InitialPhi(scenario, nullptr), ranges,
        [](bool warning, const std::string& text) { warning ? spdlog::warn("{}", text) : spdlog::info("{}", text); });
    if (device->started_from_read_back()) spdlog::info("starting where the device's channels read back");
    return device;
  }

  /// A device that cannot ramp gets no rates: the driver describes no ramps, and controllers
  /// compensate the latency instead.
  static DriverSettings WithDeviceRamps(DriverSettings settings, const WaveplateBackend& backend) {
    if (!backend.ramps()) settings.max_ramp_s = 0.0;
    return settings;
  }

  /// Where the device's record says the waveplates are (inside the ranges), else the
  /// scenario's initial φ.
  static ControlVector InitialPhi(const ScenarioConfig& scenario, const DeviceRecord* record) {
    ControlVector phi = BuildInitialPhi(scenario.controller, ScenarioControlCount(scenario.stages));
    if (record != nullptr) {
      if (auto last = record->LastPhi()) {
        phi = *last;
        spdlog::info("starting where the waveplates were left ({})", record->path());
      }
    }
    BuildChain(scenario.stages).ClampToRanges(&phi);
    return phi;
  }

  /// Under mutex_.
  void Publish(DriverState state) {
    state.publish_time_ns = WallClockNs();  // after applying: the loop's last timestamp
    bus::WriteState(state, bench_id_, &state_message_);
    state_writer_->Write(state_message_);
    if (state.mode == DriverMode::kActive) progress_ns_ = MonotonicNs();
    if (state.reason != last_reason_) {
      // Keyed by the reason without its figures: every change of what the driver does and why
      // (obeys whom; holds because nobody came yet, or because the obeyed controller went
      // silent) is logged when it first happens, and a reason that only changes its figures
      // (silent for 3.2 ms, 41.7 ms, …) at most every few seconds, with the count it stands for.
      last_reason_ = state.reason;
      const bool holding = state.mode == DriverMode::kHolding;
      log_.Log(holding ? spdlog::level::warn : spdlog::level::info, LogLimiter::KeyOf(last_reason_),
               last_reason_);
    }
  }

  void OnSample(const msg::StokesSample& message, const fdds::SampleInfo& info) {
    BenchSample sample;
    if (!bus::ReadSample(message, &sample).empty()) return;  // the controllers report those
    std::lock_guard<std::mutex> lock(mutex_);
    // One polarimeter: samples of another participant (numbered near 2⁶⁴, say) would make every
    // real one look like a new run and every command answer an unknown sample (SourceBinding).
    if (!participant_->AcceptFrom(&sample_source_, bus::SourceOf(info))) {
      log_.Log(spdlog::level::warn, "foreign sample", sample_source_.Refusal("sample", "polarimeter"));
      return;
    }
    if (core_.OnSample(sample.sequence, sample.time_ns, sample.publish_time_ns)) {
      log_.Log(spdlog::level::info, "new run", fmt::format("the bench started a new run (sample {})", sample.sequence));
    }
  }

  /// `partition`: its writer's. The controller id must be the one the partition names: with
  /// DDS Security, only that controller's identity may write there (its permissions).
  void OnCommand(const msg::WaveplateCommand& message, const std::string& partition) {
    const int64_t wall_ns = WallClockNs();
    std::lock_guard<std::mutex> lock(mutex_);
    std::string malformed = bus::ReadCommand(message, core_.control_count(), &command_);
    const std::string writer_id = bus::ControllerOfPartition(bench_id_, partition);
    if (writer_id != command_.controller_id) {
      // Counted against its real writer (never the controller it names).
      if (malformed.empty()) {
        malformed = fmt::format("controller id \"{}\" is not its writer's (partition \"{}\")",
                                command_.controller_id, partition);
      }
      command_.controller_id = writer_id.empty() ? "(unknown writer)" : writer_id;
    }
    auto state = malformed.empty()
                     ? core_.OnCommand(command_, MonotonicNs(), wall_ns)
                     : core_.OnMalformedCommand(command_.controller_id, command_.answers_sample, malformed, wall_ns);
    if (state) Publish(std::move(*state));
    rejections_.Update(core_.commands_rejected(), core_.last_rejection());
    WakeTickerIfSooner();
  }

  /// Under mutex_: a command may have brought the core's next deadline forward (a standby
  /// answered a sample the obeyed controller owes): the ticker must not sleep past it.
  void WakeTickerIfSooner() {
    const int64_t due_ns = std::max(core_.NextTickNs(), last_tick_ns_ + tick_ns_);
    if (due_ns >= tick_due_ns_) return;
    tick_due_ns_ = due_ns;
    tick_wake_.notify_one();
  }

  /// Without mutex_ (stop() may come from a callback that holds it): a wake-up lost between the
  /// ticker's check and its wait costs at most its longest sleep.
  void OnStop() override { tick_wake_.notify_all(); }

  void OnTarget(const msg::Target& message, const fdds::SampleInfo& info) {
    const auto writer = info.sample_identity.writer_guid();
    const auto own = participant_->raw()->guid();
    if (writer.guidPrefix == own.guidPrefix) return;
    const uint64_t mine = EpochOf(targets_revision_.load());
    const uint64_t theirs = EpochOf(message.revision());
    // Who started first: the epochs (whole seconds); within the same second, the write times of
    // both drivers' first targets (each writes its revision 1 as it starts); the participant
    // GUIDs only if one of them already changed its target.
    double started_before_s = static_cast<double>(mine) - static_cast<double>(theirs);
    bool i_am_later = mine > theirs;
    if (mine == theirs) {
      if (RevisionCount(message.revision()) == 1) {
        started_before_s = static_cast<double>(first_target_ns_ - info.source_timestamp.to_ns()) * 1e-9;
        i_am_later = started_before_s > 0.0 || (started_before_s == 0.0 && writer.guidPrefix < own.guidPrefix);
      } else {
        i_am_later = writer.guidPrefix < own.guidPrefix;
      }
    }
    const bool starting = MonotonicNs() - started_monotonic_ns_ <= kYieldWindowNs;
    std::lock_guard<std::mutex> lock(mutex_);
    log_.Log(spdlog::level::err, "second driver",
             fmt::format("a second driver on bench {} (participant {}, started {:.3g} s {} this one){}", bench_id_,
                         SourceName(bus::SourceOf(info)), std::abs(started_before_s),
                         i_am_later ? "before" : "after",
                         i_am_later && !starting ? ": ignored, this driver has been driving the waveplates" : ""));
    if (i_am_later && starting && !displaced_.exchange(true)) stop();
  }

  static uint64_t EpochOf(uint64_t revision) { return revision >> 32; }

  void OnTargetRequest(const msg::TargetRequest& request) {
    const std::string request_id = request.request_id().to_string();
    std::lock_guard<std::mutex> lock(mutex_);
    TargetAuthority::Reply reply;
    try {
      reply = targets_.Request(request_id, bus::TargetFromRequest(request));
    } catch (const std::exception& e) {  // an unknown kind, an invalid target
      reply = targets_.Refuse(request_id, e.what());
    }
    if (reply.accepted) {
      target_writer_->Write(bus::TargetMessage(targets_.current(), bench_id_));
      spdlog::info("target revision {} (request {})", reply.revision, request_id);
    } else {
      log_.Log(spdlog::level::warn, "refused target request",
               fmt::format("refused target request {}: {}", request_id, reply.message));
    }
    msg::TargetReply out;
    out.bench_id(bench_id_);
    out.request_id(request_id);
    out.accepted(reply.accepted);
    out.revision(reply.revision);
    out.message(reply.message.substr(0, 255));
    reply_writer_->Write(out);
  }

  std::string bench_id_;
  int64_t tick_ns_;
  // The ticker's schedule, under mutex_.
  std::condition_variable tick_wake_;
  int64_t tick_due_ns_ = 0;
  int64_t last_tick_ns_ = 0;
  ScenarioConfig scenario_;
  std::unique_ptr<DeviceRecord> record_;
  std::unique_ptr<WaveplateBackend> backend_;
  std::mutex mutex_;             ///< the core, the target authority and the messages below
  DriverCore core_;
  TargetAuthority targets_;
  ControllerCommand command_;    ///< read into in place
  msg::WaveplateState state_message_;  ///< written in place: no allocation per state
  std::string last_reason_;
  RejectionLog rejections_{"rejected command"};
  SourceBinding sample_source_{kSourceReleaseNs};  ///< the polarimeter's participant; under mutex_
  LogLimiter log_;  ///< under mutex_
  msg::DeviceDescription device_message_;  ///< written by every participant this driver makes
  bus::ParticipantMaker maker_;
  /// Replaced only by a reload, while no reader exists (the readers' callbacks use it).
  std::unique_ptr<bus::BusParticipant> participant_;
  std::unique_ptr<bus::Writer<msg::WaveplateState>> state_writer_;
  std::unique_ptr<bus::Writer<msg::DeviceDescription>> device_writer_;
  std::unique_ptr<bus::Writer<msg::Target>> target_writer_;
  std::unique_ptr<bus::Writer<msg::TargetReply>> reply_writer_;
  std::unique_ptr<bus::Reader<msg::StokesSample>> samples_;
  std::unique_ptr<bus::Reader<msg::WaveplateCommand>> commands_;
  std::unique_ptr<bus::Reader<msg::TargetRequest>> requests_;
  std::unique_ptr<bus::Reader<msg::Target>> others_;  ///< other drivers' targets
  std::atomic<uint64_t> targets_revision_{0};  ///< the first revision this driver published
  /// How long after its start a driver yields to another one that started earlier: the
  /// incumbent's TRANSIENT_LOCAL target reaches a newcomer within discovery (tens of ms on
  /// loopback, a second or so with security handshakes or unicast peers).
  static constexpr int64_t kYieldWindowNs = 3'000'000'000;
  int64_t first_target_ns_ = 0;  ///< wall clock when it was written (set before any reader exists)
  int64_t started_monotonic_ns_ = 0;  ///< monotonic clock then
  int64_t progress_ns_ = MonotonicNs();  ///< the latest state applying a command (start: none yet); mutex_
  std::atomic<bool> displaced_{false};
};

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) {
  return dpc::services::ServiceMain<dpc::services::DriverService>(
      argc, argv, "dpc-driver: the bench's waveplate driver (obeys one controller, publishes the state)");
}
