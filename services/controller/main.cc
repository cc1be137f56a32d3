// dpc-controller: a Jacobian controller. Configures itself from the bus (device description,
// target), answers every polarimeter sample with a command, follows the applied φ while another
// controller is obeyed (bumpless takeover), and publishes its status.
//
//   dpc-controller [SCENARIO] [--id ID] [--priority P] [--method gp] [--step 0.5] …

#include <mutex>

#include <spdlog/spdlog.h>

#include "controller_core.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bench/clock.h"
#include "dpc/config/scenario_error.h"
#include "service_runtime.h"

namespace dpc::services {
namespace {

int Run(int argc, char** argv) {
  ShutdownSignals signals;
  CLI::App app{"dpc-controller: a Jacobian polarization controller on the bench's DDS bus"};
  CommonOptions common;
  AddCommonOptions(app, &common);
  ControllerSettings settings;
  app.add_option("--id", settings.controller_id, "Controller id (unique on the bench)")
      ->check([](const std::string& id) -> std::string {
        return id.empty() || id.size() > 63 ? "controller id must have 1 to 63 characters" : "";
      })
      ->capture_default_str();
  app.add_option("--priority", settings.priority,
                 "The driver obeys the alive controller of highest priority")
      ->capture_default_str();
  app.add_option("--freeze-after-s", settings.freeze_after_s,
                 "A gap in the samples longer than this freezes the loop; it re-joins from the "
                 "applied φ when samples resume")
      ->check(CLI::Range(1e-4, 60.0))->capture_default_str();
  std::string predict_mode = "ramp";
  app.add_option("--predict-mode", predict_mode,
                 "With --predict in real time: 'ramp' (commands carry φ̇ from the fitted input "
                 "rotation; the driver moves along it) or 'latency' (aim at the input predicted "
                 "across the measured loop latency). Ramp falls back to latency if the driver "
                 "does not ramp")
      ->check(CLI::IsMember({"ramp", "latency"}))->capture_default_str();
  double status_period_s = 0.02;
  app.add_option("--status-period-s", status_period_s, "Status publication period")
      ->check(CLI::Range(1e-3, 10.0))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  settings.prediction_mode = predict_mode == "latency" ? PredictionMode::kLatency : PredictionMode::kRamp;
  SetUpLogging("controller " + settings.controller_id, common);
  try {
    const ScenarioConfig scenario = LoadServiceScenario(common);
    settings.controller = scenario.controller;
    settings.simulation = scenario.simulation;
  } catch (const ScenarioError& e) {
    spdlog::error("{}", DescribeError(e, common));
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  }

  try {
    ControllerCore core(settings);
    std::mutex mutex;
    bus::BusParticipant participant({common.domain_id, "dpc-controller/" + settings.controller_id});
    auto command_writer = participant.MakeWriter<msg::WaveplateCommand>();
    auto status_writer = participant.MakeWriter<msg::ControllerStatus>();
    auto devices = participant.MakeReader<msg::DeviceDescription>(
        common.bench_id, [&](const msg::DeviceDescription& message, const auto&) {
          DeviceDescription description;
          const std::string unreadable = bus::ReadDevice(message, &description);
          std::lock_guard<std::mutex> lock(mutex);
          if (!unreadable.empty()) {
            core.OnUnusableDevice(unreadable);
            spdlog::error("unusable device description: {}", unreadable);
          } else if (std::string error = core.OnDevice(description); !error.empty()) {
            spdlog::error("{}", error);
          } else {
            spdlog::info("device: {} stages from driver {}", description.stages.size(), description.driver_id);
          }
        });
    auto targets = participant.MakeReader<msg::Target>(
        common.bench_id, [&](const msg::Target& message, const auto&) {
          BenchTarget target;
          const std::string unreadable = bus::ReadTarget(message, &target);
          std::lock_guard<std::mutex> lock(mutex);
          if (!unreadable.empty()) {
            core.OnUnusableTarget(unreadable);
            spdlog::error("unusable target: {}", unreadable);
          } else if (std::string error = core.OnTarget(target); !error.empty()) {
            spdlog::error("{}", error);
          } else {
            spdlog::info("target revision {}", target.revision);
          }
        });
    RejectionLog rejections("rejected sample or state");
    DriverState state;  // read into in place, under the lock
    auto states = participant.MakeReader<msg::WaveplateState>(
        common.bench_id, [&](const msg::WaveplateState& message, const auto&) {
          std::lock_guard<std::mutex> lock(mutex);
          if (core.control_count() == 0) return;  // no device yet
          if (std::string reason = bus::ReadState(message, core.control_count(), &state); !reason.empty()) {
            core.RejectInput("state: " + reason);
          } else {
            core.OnState(state);
          }
          rejections.Update(core.rejected_samples(), core.last_rejection());
        });
    BenchSample sample;
    msg::WaveplateCommand command_message;  // written in place: no allocation per command
    std::unique_ptr<bus::Reader<msg::StokesSample>> samples;
    samples = participant.MakeReader<msg::StokesSample>(
        common.bench_id, [&](const msg::StokesSample& message, const auto&) {
          const int64_t wall_ns = WallClockNs();
          std::lock_guard<std::mutex> lock(mutex);
          if (std::string reason = bus::ReadSample(message, &sample); !reason.empty()) {
            core.RejectInput(reason);
          } else if (const ControllerCommand* command = core.OnSample(sample, MonotonicNs(), wall_ns)) {
            bus::WriteCommand(*command, common.bench_id, &command_message);
            command_writer->Write(command_message);
          }
          rejections.Update(core.rejected_samples(), core.last_rejection());
        });
    spdlog::info("law {}, priority {}, profiles {}, domain {}",
                 MethodName(settings.controller.method), settings.priority,
                 participant.profiles_file(), common.domain_id);
    std::string last_condition;
    const auto period = std::chrono::milliseconds(static_cast<int64_t>(status_period_s * 1000));
    while (!signals.Wait(period)) {
      std::lock_guard<std::mutex> lock(mutex);
      const ControllerStatusReport status = core.TakeStatus(
          MonotonicNs(), WallClockNs(), samples->counters().deadline_misses.load());
      status_writer->Write(bus::StatusMessage(status, common.bench_id));
      if (status.condition != last_condition) {
        last_condition = status.condition;
        spdlog::info("{}{}", last_condition, status.obeyed ? " (obeyed)" : "");
      }
    }
    samples.reset();
    states.reset();
    targets.reset();
    devices.reset();
    spdlog::info("stopping on signal {}", signals.signal());
  } catch (const bus::BusError& e) {
    spdlog::error("{}", e.what());
    return cli::ToInt(cli::ExitCode::kRuntimeError);
  }
  return cli::ToInt(cli::ExitCode::kOk);
}

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) { return dpc::services::Run(argc, argv); }
