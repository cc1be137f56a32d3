// dpc-controller: a Jacobian controller. Configures itself from the bus (device description,
// target), answers every polarimeter sample with a command, follows the applied φ while another
// controller is obeyed (bumpless takeover), and publishes its status.
//
//   dpc-controller [SCENARIO] [--id ID] [--priority P] [--method gp] [--step 0.5] …

#include <atomic>
#include <memory>
#include <mutex>

#include <spdlog/spdlog.h>

#include "controller_core.h"
#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/event_thread_canary.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/participant_maker.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/cli/command_line.h"
#include "log_limiter.h"
#include "service.h"

namespace dpc::services {
namespace {

namespace fdds = eprosima::fastdds::dds;

class ControllerService final : public Service {
 public:
  struct Options {
    ControllerSettings settings;
    std::string predict_mode = "ramp";
    double status_period_s = 0.02;
  };

  static void AddOptions(CLI::App& app, Options* o) {
    ControllerSettings& s = o->settings;
    app.add_option("--id", s.controller_id, "Controller id (unique on the bench)")
        ->check([](const std::string& id) { return IdentifierProblem(id); })
        ->capture_default_str();
    app.add_option("--priority", s.priority, "The driver obeys the alive controller of highest priority")
        ->capture_default_str();
    app.add_option("--freeze-after-s", s.freeze_after_s,
                   "A gap in the samples longer than this freezes the loop; it re-joins from the "
                   "applied φ when samples resume")
        ->check(cli::NumberIn(1e-4, 60.0))->capture_default_str();
    app.add_option("--predict-mode", o->predict_mode,
                   "With --predict in real time: 'ramp' (commands carry φ̇ from the fitted input "
                   "rotation; the driver moves along it) or 'latency' (aim at the input predicted "
                   "across the measured loop latency). Ramp falls back to latency if the driver "
                   "does not ramp")
        ->check(CLI::IsMember({"ramp", "latency"}))->capture_default_str();
    app.add_option("--status-period-s", o->status_period_s, "Status publication period")
        ->check(cli::NumberIn(1e-3, 10.0))->capture_default_str();
  }
  static std::string LogName(const Options& o) { return "controller " + o.settings.controller_id; }

  ControllerService(const CommonOptions& common, const Options& options)
      : bench_id_(common.bench_id),
        status_period_(std::chrono::milliseconds(static_cast<int64_t>(options.status_period_s * 1000))),
        core_(Settings(common, options)),
        maker_({common.domain_id, "dpc-controller/" + options.settings.controller_id,
                {common.security_dir,
                 common.identity.empty() ? "controller-" + options.settings.controller_id : common.identity}},
               bus::DescribedPeerEvents(PeerLogger()), LogLine),
        participant_(maker_.Make()) {
    MakeEndpoints();
    for (const std::string& line : bus::DescribeShmCleanup(participant_->shm_cleanup())) spdlog::info("{}", line);
    spdlog::info("law {}, priority {}, profiles {}, domain {}", MethodName(core_settings_.controller.method),
                 core_settings_.priority, participant_->profiles_file(), common.domain_id);
  }

  ~ControllerService() override { DeleteEndpoints(); }

  /// A turn waits one status period.
  std::optional<double> LongestTurnS() const override {
    return std::chrono::duration<double>(status_period_).count();
  }
  cli::Heartbeat GuardHeartbeat() const override {
    return {bus::OldestEventThreadTickNs, bus::kEventThreadStuckS, bus::kEventThreadWhat};
  }

  /// Publishes the status every --status-period-s until stop(); a reload (SIGHUP) is done here,
  /// between two statuses.
  cli::ExitCode run() override {
    std::string last_condition;
    GuardPhase("its status loop");
    maker_.SetPhaseReport([this](const char* phase) { return GuardPhase(phase); });
    while (!WaitForStopFor(status_period_)) {
      Turned();
      // A SIGHUP, or a handshake stall: progress is a command written, which needs the driver's
      // description and the polarimeter's samples, which a stalled handshake with either
      // withholds. The controller answers no sample until its new readers are matched; the
      // driver meanwhile treats it as silent.
      if (const auto cause =
              maker_.ReloadCause(TakeReloadRequest(), *participant_, MonotonicNs(), progress_ns_.load())) {
        maker_.Reload(&participant_, [this] { DeleteEndpoints(); }, [this] { MakeEndpoints(); }, *cause);
      }
      std::lock_guard<std::mutex> lock(mutex_);
      const ControllerStatusReport status =
          core_.TakeStatus(MonotonicNs(), WallClockNs(), samples_->counters().deadline_misses.load());
      status_writer_->Write(bus::StatusMessage(status, bench_id_));
      if (status.condition != last_condition) {
        // A condition that changes within its kind ("frozen: no sample for 25 ms", … 45 ms) is
        // logged at most every few seconds, with the count of changes it stands for.
        last_condition = status.condition;
        log_.Log(spdlog::level::info, LogLimiter::KindOf(last_condition),
                 last_condition + (status.obeyed ? " (obeyed)" : ""));
      }
    }
    return cli::ExitCode::kOk;
  }

 private:
  /// On the status loop's thread, without mutex_ (the readers' callbacks take it): the writers on
  /// participant_, then the readers (a sample's callback writes the command).
  void MakeEndpoints() {
    command_writer_ = participant_->MakeWriter<msg::WaveplateCommand>(bench_id_, core_settings_.controller_id);
    status_writer_ = participant_->MakeWriter<msg::ControllerStatus>(bench_id_);
    devices_ = participant_->MakeReader<msg::DeviceDescription>(
        bench_id_, [this](const msg::DeviceDescription& message, const auto& info) { OnDevice(message, info); });
    targets_ = participant_->MakeReader<msg::Target>(
        bench_id_, [this](const msg::Target& message, const auto& info) { OnTarget(message, info); });
    states_ = participant_->MakeReader<msg::WaveplateState>(
        bench_id_, [this](const msg::WaveplateState& message, const auto& info) { OnState(message, info); });
    // The status reports the sample topic's missed deadlines: this reader requests it.
    samples_ = participant_->MakeReader<msg::StokesSample>(
        bench_id_, [this](const msg::StokesSample& message, const auto& info) { OnSample(message, info); },
        bus::DeadlineWatch::kOn);
  }

  /// Without mutex_: the readers first (their callbacks take it and use the core and the
  /// command writer; deleting a reader waits for its callback), then the writers.
  void DeleteEndpoints() {
    samples_.reset();
    states_.reset();
    targets_.reset();
    devices_.reset();
    command_writer_.reset();
    status_writer_.reset();
  }

  /// The core's settings: the options, and the scenario's controller and simulation sections
  /// (the scenario validated whole, as `dpc sim` does: ScenarioError).
  ControllerSettings Settings(const CommonOptions& common, const Options& options) {
    ScenarioConfig scenario = LoadServiceScenario(common);
    ValidateScenario(scenario);
    core_settings_ = options.settings;
    core_settings_.controller = scenario.controller;
    core_settings_.simulation = scenario.simulation;
    core_settings_.prediction_mode =
        options.predict_mode == "latency" ? PredictionMode::kLatency : PredictionMode::kRamp;
    return core_settings_;
  }

  /// Whether the writer of a received `what` is the bench's `who` (the bound source of
  /// `binding`, under mutex_): if not, the message is refused, counted and reported.
  bool FromBoundSource(SourceBinding* binding, const fdds::SampleInfo& info, const char* what, const char* who) {
    if (participant_->AcceptFrom(binding, bus::SourceOf(info))) return true;
    core_.RejectInput(binding->Refusal(what, who));
    log_.Log(spdlog::level::warn, std::string("foreign ") + what, core_.last_rejection());
    return false;
  }

  void OnDevice(const msg::DeviceDescription& message, const fdds::SampleInfo& info) {
    DeviceDescription description;
    const std::string unreadable = bus::ReadDevice(message, &description);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!FromBoundSource(&driver_source_, info, "device description", "driver")) return;
    if (!unreadable.empty()) {
      core_.OnUnusableDevice(unreadable);
      log_.Log(spdlog::level::err, "unusable device", "unusable device description: " + unreadable);
    } else if (std::string error = core_.OnDevice(description); !error.empty()) {
      log_.Log(spdlog::level::err, "unusable device", error);
    } else {
      log_.Log(spdlog::level::info, "device",
               fmt::format("device: {} stages from driver {}", description.stages.size(), description.driver_id));
    }
  }

  void OnTarget(const msg::Target& message, const fdds::SampleInfo& info) {
    BenchTarget target;
    const std::string unreadable = bus::ReadTarget(message, &target);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!FromBoundSource(&driver_source_, info, "target", "driver")) return;
    if (!unreadable.empty()) {
      core_.OnUnusableTarget(unreadable);
      log_.Log(spdlog::level::err, "unusable target", "unusable target: " + unreadable);
    } else if (std::string error = core_.OnTarget(target); !error.empty()) {
      log_.Log(spdlog::level::err, "unusable target", error);
    } else {
      log_.Log(spdlog::level::info, "target", fmt::format("target revision {}", target.revision));
    }
  }

  void OnState(const msg::WaveplateState& message, const fdds::SampleInfo& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!FromBoundSource(&driver_source_, info, "state", "driver")) {
      rejections_.Update(core_.rejected_samples(), core_.last_rejection());
      return;
    }
    if (core_.control_count() == 0) return;  // no device yet
    if (std::string reason = bus::ReadState(message, core_.control_count(), &state_); !reason.empty()) {
      core_.RejectInput("state: " + reason);
    } else {
      core_.OnState(state_);
    }
    rejections_.Update(core_.rejected_samples(), core_.last_rejection());
  }

  void OnSample(const msg::StokesSample& message, const fdds::SampleInfo& info) {
    const int64_t wall_ns = WallClockNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::string reason = bus::ReadSample(message, &sample_); !reason.empty()) {
      core_.RejectInput(reason);  // malformed, whoever sent it
    } else if (!FromBoundSource(&sample_source_, info, "sample", "polarimeter")) {
      // counted and reported
    } else if (const ControllerCommand* command = core_.OnSample(sample_, MonotonicNs(), wall_ns)) {
      bus::WriteCommand(*command, bench_id_, &command_message_);
      command_writer_->Write(command_message_);
      progress_ns_.store(MonotonicNs(), std::memory_order_relaxed);
    }
    rejections_.Update(core_.rejected_samples(), core_.last_rejection());
  }

  std::string bench_id_;
  std::chrono::milliseconds status_period_;
  ControllerSettings core_settings_;
  std::mutex mutex_;                 ///< the core and the messages below
  std::atomic<int64_t> progress_ns_{MonotonicNs()};  ///< the latest command written (start: none yet)
  ControllerCore core_;
  DriverState state_;                ///< read into in place
  BenchSample sample_;
  msg::WaveplateCommand command_message_;  ///< written in place: no allocation per command
  RejectionLog rejections_{"rejected sample or state"};
  /// Who the device description, the target and the states come from (the driver's participant),
  /// and the samples (the polarimeter's): SourceBinding. Under mutex_.
  SourceBinding driver_source_{kSourceReleaseNs};
  SourceBinding sample_source_{kSourceReleaseNs};
  LogLimiter log_;  ///< under mutex_ (the status loop holds it too)
  bus::ParticipantMaker maker_;
  /// Replaced only by a reload, while no reader exists.
  std::unique_ptr<bus::BusParticipant> participant_;
  std::unique_ptr<bus::Writer<msg::WaveplateCommand>> command_writer_;
  std::unique_ptr<bus::Writer<msg::ControllerStatus>> status_writer_;
  std::unique_ptr<bus::Reader<msg::DeviceDescription>> devices_;
  std::unique_ptr<bus::Reader<msg::Target>> targets_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> states_;
  std::unique_ptr<bus::Reader<msg::StokesSample>> samples_;
};

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) {
  return dpc::services::ServiceMain<dpc::services::ControllerService>(
      argc, argv, "dpc-controller: a Jacobian polarization controller on the bench's DDS bus");
}
