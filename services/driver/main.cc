// dpc-driver: the waveplate driver. Obeys one controller (priority, liveness), validates,
// clamps and slew-limits its commands, applies them to the backend (the simulated device) and
// publishes the state; owns the device description and the target on the bus.
//
//   dpc-driver [SCENARIO] [--domain N] [--bench-id ID] [--max-slew-per-s X] [--min-silence-s T]

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>

#include <spdlog/spdlog.h>

#include "driver_core.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bench/clock.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"
#include "service_runtime.h"

namespace dpc::services {
namespace {

int Run(int argc, char** argv) {
  ShutdownSignals signals;
  CLI::App app{"dpc-driver: the bench's waveplate driver (obeys one controller, publishes the state)"};
  CommonOptions common;
  AddCommonOptions(app, &common);
  DriverSettings settings;
  app.add_option("--id", settings.driver_id, "Driver id")->capture_default_str();
  app.add_option("--max-slew-per-s", settings.max_slew_per_s,
                 "Slew-rate limit of every control, φ units per second of the driver's clock (0: "
                 "the device's own limit; a value above it is cut to it)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--min-silence-s", settings.min_silence_s,
                 "The obeyed controller is dead when another answered a sample it did not this long ago "
                 "(or --silence-intervals of its command interval, if longer): fail over. If "
                 "nobody answers for this long (no samples, no other controller), hold; the "
                 "controller obeyed before gets control back first")
      ->check(CLI::Range(1e-4, 10.0))->capture_default_str();

  app.add_option("--silence-intervals", settings.silence_intervals,
                 "Silence timeout in command intervals")
      ->check(CLI::Range(2.0, 1000.0))->capture_default_str();
  app.add_option("--max-ramp-s", settings.max_ramp_s,
                 "A command's rate (phi_rate_per_s) moves the waveplates for at most this long of "
                 "bench time; the next command normally replaces it long before")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  double tick_s = 2.5e-4;
  app.add_option("--tick-s", tick_s, "Shortest interval between the driver's checks for silent controllers")
      ->check(CLI::Range(1e-5, 0.1))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  SetUpLogging("driver", common);

  ScenarioConfig scenario;
  ControlVector initial_phi;
  try {
    scenario = LoadServiceScenario(common);
    ValidateDeviceStages(scenario.stages);
    ValidateTargetConfig(scenario.target);
    const int controls = ScenarioControlCount(scenario.stages);
    if (!scenario.controller.initial_phi.empty() &&
        scenario.controller.initial_phi.size() != static_cast<size_t>(controls)) {
      throw ScenarioError("controller.initial_phi",
                          fmt::format("has {} values, the device has {} controls",
                                      scenario.controller.initial_phi.size(), controls));
    }
    initial_phi = BuildInitialPhi(scenario.controller, controls);
    BuildChain(scenario.stages).ClampToRanges(&initial_phi);
  } catch (const ScenarioError& e) {
    spdlog::error("invalid scenario: {}", e.what());
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  }

  try {
    SimulatedWaveplates backend(initial_phi);
    DriverCore core(scenario.stages, settings, &backend);
    std::mutex mutex;
    bus::BusParticipant participant({common.domain_id, "dpc-driver/" + common.bench_id});
    auto state_writer = participant.MakeWriter<msg::WaveplateState>();
    auto device_writer = participant.MakeWriter<msg::DeviceDescription>();
    auto target_writer = participant.MakeWriter<msg::Target>();
    auto reply_writer = participant.MakeWriter<msg::TargetReply>();
    device_writer->Write(bus::DeviceMessage(
        DeviceDescription{settings.driver_id, scenario.stages, core.max_slew_per_s(), settings.max_ramp_s},
        common.bench_id));
    uint64_t target_revision = 1;
    target_writer->Write(bus::TargetMessage(BenchTarget{target_revision, "", scenario.target}, common.bench_id));

    std::string last_reason;
    msg::WaveplateState state_message;  // written in place: no allocation per state
    auto publish = [&](DriverState state) {
      state.publish_time_ns = WallClockNs();  // after applying: the loop's last timestamp
      bus::WriteState(state, common.bench_id, &state_message);
      state_writer->Write(state_message);
      if (state.reason != last_reason) {
        last_reason = state.reason;
        if (state.mode == DriverMode::kHolding) {
          spdlog::warn("{}", last_reason);
        } else {
          spdlog::info("{}", last_reason);
        }
      }
    };
    {
      std::lock_guard<std::mutex> lock(mutex);
      publish(core.Publishable(WallClockNs()));
    }
    // The driver's own record of the bench's samples: a command is judged by it (SampleTimeline).
    auto samples = participant.MakeReader<msg::StokesSample>(
        common.bench_id, [&](const msg::StokesSample& message, const auto&) {
          BenchSample sample;
          if (!bus::ReadSample(message, &sample).empty()) return;  // the controllers report those
          std::lock_guard<std::mutex> lock(mutex);
          if (core.OnSample(sample.sequence, sample.time_ns, sample.publish_time_ns)) {
            spdlog::info("the bench started a new run (sample {})", sample.sequence);
          }
        });
    RejectionLog rejections("rejected command");
    ControllerCommand command;  // read into in place, under the lock
    auto commands = participant.MakeReader<msg::WaveplateCommand>(
        common.bench_id, [&](const msg::WaveplateCommand& message, const auto&) {
          const int64_t wall_ns = WallClockNs();
          std::lock_guard<std::mutex> lock(mutex);
          const std::string malformed = bus::ReadCommand(message, core.control_count(), &command);
          auto state = malformed.empty()
                           ? core.OnCommand(command, MonotonicNs(), wall_ns)
                           : core.OnMalformedCommand(command.controller_id, command.answers_sample, malformed, wall_ns);
          if (state) publish(std::move(*state));
          rejections.Update(core.commands_rejected(), core.last_rejection());
        });
    auto requests = participant.MakeReader<msg::TargetRequest>(
        common.bench_id, [&](const msg::TargetRequest& request, const auto&) {
          msg::TargetReply reply;
          reply.bench_id(common.bench_id);
          reply.request_id(request.request_id());
          try {
            const TargetConfig target = bus::TargetFromRequest(request);
            std::lock_guard<std::mutex> lock(mutex);
            ++target_revision;
            target_writer->Write(bus::TargetMessage(
                BenchTarget{target_revision, request.request_id().to_string(), target}, common.bench_id));
            reply.accepted(true);
            reply.revision(target_revision);
            reply.message("target revision " + std::to_string(target_revision));
            spdlog::info("target revision {} (request {})", target_revision,
                         request.request_id().to_string());
          } catch (const std::exception& e) {
            reply.accepted(false);
            reply.message(std::string(e.what()).substr(0, 255));
            spdlog::warn("refused target request {}: {}", request.request_id().to_string(), e.what());
          }
          reply_writer->Write(reply);
        });

    std::atomic<bool> stop{false};
    // The ticker wakes when the obeyed controller's silence deadline (or the holding heartbeat)
    // is due, at most every --tick-s: while commands flow, about once per silence timeout.
    std::thread ticker([&] {
      const int64_t tick_ns = static_cast<int64_t>(tick_s * 1e9);
      const int64_t max_sleep_ns = 5'000'000;
      while (!stop.load()) {
        int64_t due_ns;
        {
          std::lock_guard<std::mutex> lock(mutex);
          const int64_t now_ns = MonotonicNs();
          if (auto state = core.Tick(now_ns, WallClockNs())) publish(*state);
          due_ns = std::clamp(core.NextTickNs(), now_ns + tick_ns, now_ns + max_sleep_ns);
        }
        std::this_thread::sleep_until(std::chrono::steady_clock::time_point(std::chrono::nanoseconds(due_ns)));
      }
    });
    spdlog::info("{} controls, profiles {}, domain {}", core.control_count(),
                 participant.profiles_file(), common.domain_id);
    while (!signals.Wait(std::chrono::milliseconds(500))) {
    }
    stop = true;
    ticker.join();
    commands.reset();
    requests.reset();
    samples.reset();
    spdlog::info("stopping on signal {}", signals.signal());
  } catch (const std::exception& e) {  // bus::BusError, or a backend the driver cannot use
    spdlog::error("{}", e.what());
    return cli::ToInt(cli::ExitCode::kRuntimeError);
  }
  return cli::ToInt(cli::ExitCode::kOk);
}

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) { return dpc::services::Run(argc, argv); }
