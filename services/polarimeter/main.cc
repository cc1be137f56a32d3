// dpc-polarimeter: the simulated optical bench and its polarimeter. Publishes a Stokes sample
// per period (real time) or per simulated sample, waiting for the answering state (lockstep).
//
//   dpc-polarimeter [SCENARIO] [--rate-hz 10000] [--run-s 0]          real time until stopped
//   dpc-polarimeter SCENARIO --lockstep [--trace FILE] [--json]       reproduces `dpc sim`
//   dpc-polarimeter … --input-recording FILE.mcap [--input-from-s T]  the input SOP of a recording
//   dpc-polarimeter SCENARIO-WITH-polarimeter_device [--rate-hz N]    a real polarimeter (serial/TCP)

#include <functional>
#include <iostream>
#include <memory>

#include <spdlog/spdlog.h>

#include "bench_core.h"
#include "dds_bench_link.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/event_thread_canary.h"
#include "dpc/bench/clock.h"
#include "dpc/bus/recorded_bench.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/run_report.h"
#include "dpc/sim/trace_header.h"
#include "dpc/sim/trace_writer.h"
#include "instrument_polarimeter.h"
#include "log_limiter.h"
#include "service.h"

namespace dpc::services {
namespace {

class TraceObserver final : public SimulationObserver {
 public:
  TraceObserver(TraceWriter* trace, const Service* service) : trace_(trace), service_(service) {}
  void OnSample(const SampleView& s) override {
    trace_->Write(s.t_s, s.s_in, s.s_out, s.error_deg, s.phi_applied);
  }
  bool wants_samples() const override { return trace_ != nullptr; }
  bool OnProgress(int64_t, int64_t) override { return !service_->stopped(); }

 private:
  TraceWriter* trace_;
  const Service* service_;
};

struct PolarimeterOptions {
  BenchSettings bench;
  double lockstep_timeout_s = 10.0;
  std::string trace_path;
  bool json = false;
  double summary_hz = 20.0;
  std::string input_recording;  ///< a dpc record file whose samples' S_in are the input
  double input_from_s = 0.0;
};

/// The scenario, with the input SOP of a recording in place of its own when one is given.
/// The lockstep's progress in the log, at most every 2 s ("lockstep: 4096 of 10000 samples"; dpc
/// evaluate shows it); each call (every 1024 samples) is also a turn for the loop guard.
PolarimeterOptions WithProgressLog(PolarimeterOptions o, std::function<void()> turned) {
  auto next_ns = std::make_shared<int64_t>(0);
  o.bench.lockstep_progress = [next_ns, turned = std::move(turned)](int64_t done, int64_t total) {
    turned();  // a lockstep run's samples before the control starts never reach the link
    const int64_t now_ns = MonotonicNs();
    if (now_ns < *next_ns) return;
    *next_ns = now_ns + 2'000'000'000;
    spdlog::info("lockstep: {} of {} samples", done, total);
  };
  return o;
}

ScenarioConfig LoadPolarimeterScenario(const CommonOptions& common, const PolarimeterOptions& o) {
  ScenarioConfig scenario = LoadServiceScenario(common);
  if (scenario.polarimeter_device) {
    // A real polarimeter measures what the optics do, in real time.
    if (o.bench.lockstep) throw ConfigurationError("--lockstep: the scenario has a polarimeter_device (a real "
                                                   "instrument measures in real time)");
    if (!o.input_recording.empty()) {
      throw ConfigurationError("--input-recording: the scenario has a polarimeter_device (the input is the "
                               "instrument's)");
    }
  }
  if (o.input_recording.empty()) return scenario;
  bus::RecordedBenchOptions read;
  read.from_s = o.input_from_s;
  read.samples_only = true;
  bus::RecordedBench recording;
  try {
    recording = bus::ReadRecordedBench(o.input_recording, read);
  } catch (const std::exception& e) {
    throw ConfigurationError(fmt::format("--input-recording: {}", e.what()));
  }
  if (recording.samples.empty()) {
    throw ConfigurationError(fmt::format("--input-recording {}: no usable sample{}{}", o.input_recording,
                                         o.input_from_s > 0 ? fmt::format(" after {} s", o.input_from_s) : "",
                                         recording.rejected > 0 ? " (last rejected: " + recording.last_rejection + ")"
                                                                : ""));
  }
  auto input = std::make_shared<RecordedInput>(recording.Input());
  const double recorded_hz = recording.SampleRateHz();
  const double bench_hz = o.bench.lockstep ? scenario.simulation.sample_rate_hz : o.bench.rate_hz;
  spdlog::info("input: {} samples of {} (bench {}, recorded at {:.0f} Hz{}{}){}", input->sops.size(),
               o.input_recording, recording.bench_id, recorded_hz,
               recording.samples_missing > 0 ? fmt::format(", {} missing samples filled with the one before",
                                                           recording.samples_missing)
                                             : "",
               recording.complete ? "" : ", the file is cut short: " + recording.problem,
               recorded_hz > 0 && std::abs(recorded_hz - bench_hz) > 0.01 * bench_hz
                   ? fmt::format("; this bench runs at {:.0f} Hz, so the recorded motion is {:.3g}× as fast", bench_hz,
                                 bench_hz / recorded_hz)
                   : "");
  scenario.input.disturbances.clear();
  scenario.input.initial_sop = input->sops.front();
  scenario.input.recorded = std::move(input);
  return scenario;
}

class PolarimeterService final : public Service {
 public:
  using Options = PolarimeterOptions;

  static void AddOptions(CLI::App& app, Options* o) {
    app.add_flag("--lockstep", o->bench.lockstep,
                 "Simulated time: wait for the state answering each sample (reproduces dpc sim)");
    app.add_option("--rate-hz", o->bench.rate_hz, "Real time: samples per second")
        ->check(cli::NumberIn(1.0, 20000.0))->capture_default_str();
    app.add_option("--run-s", o->bench.duration_s, "Real time: stop after this long (0: until stopped)")
        ->check(cli::NonNegativeNumber())->capture_default_str();
    app.add_option("--settle-s", o->bench.settle_s,
                   "Real time: error statistics from this long after the first lock, the loop "
                   "latency (bench.loop_latency_us) from this long after the start")
        ->check(cli::NonNegativeNumber())->capture_default_str();
    app.add_option("--lockstep-timeout-s", o->lockstep_timeout_s,
                   "Lockstep: give up when no state answers a sample for this long")
        ->check(cli::NumberIn(0.1, 3600.0))->capture_default_str();
    app.add_option("--trace", o->trace_path, "Write every sample to this CSV trace (dpc sim's format)");
    app.add_flag("--json", o->json, "Print the run's summary as one JSON object (dpc sim's fields)");
    app.add_option("--summary-hz", o->summary_hz,
                   "Summaries of the bench per second on dpc_bench_summary (for dpc dashboard; 0: none)")
        ->check(cli::NumberIn(0.0, 100.0))->capture_default_str();
    app.add_option("--input-recording", o->input_recording,
                   "The input SOP of a recorded session (dpc record's .mcap): S_in of its samples, one per "
                   "sample of this bench, in place of the scenario's input; the last one held past its end")
        ->check(CLI::ExistingFile);
    app.add_option("--input-from-s", o->input_from_s,
                   "With --input-recording: start this far into the recording (its bench time)")
        ->check(cli::NonNegativeNumber())->capture_default_str();
  }
  static std::string LogName(const Options&) { return "polarimeter"; }

  PolarimeterService(const CommonOptions& common, const Options& options)
      : options_(options),
        bench_(LoadPolarimeterScenario(common, options), WithProgressLog(options, [this] { Turned(); }).bench),  // validates: ScenarioError

        // The loop latency is counted, like the error, once the loop has settled: in real time
        // from --settle-s into the run (the first samples meet a controller re-joining and
        // processes touching fresh pages: single stalls of several ms); in lockstep from the start.
        link_(bus::ParticipantMaker({common.domain_id, "dpc-polarimeter/" + common.bench_id,
                                     {common.security_dir, common.identity.empty() ? "polarimeter" : common.identity}},
                                    bus::DescribedPeerEvents(PeerLogger()), LogLine),
              bench_.control_count(), common.bench_id, options.lockstep_timeout_s,
              options.bench.lockstep ? 0.0 : options.bench.settle_s, options.summary_hz,
              bench_.scenario().target) {
    if (bench_.scenario().polarimeter_device) {
      instrument_ = std::make_unique<InstrumentPolarimeter>(*bench_.scenario().polarimeter_device);
      const PolarimeterDeviceConfig& device = instrument_->device();
      if (device.stream) {
        spdlog::info("samples from {} (its stream, started by {})", instrument_->name(),
                     device.stream_start.empty() ? std::string("the instrument itself") : device.stream_start);
      } else {
        spdlog::info("samples from {} ({} per sample)", instrument_->name(), device.query);
      }
    }
    if (!options.trace_path.empty()) {
      std::vector<std::string> names;
      for (const auto& c : bench_.chain().controls()) names.push_back(c.name);
      // dpc sim's header (dpc plot redraws the trace), and who wrote it.
      trace_ = std::make_unique<TraceWriter>(
          options.trace_path, names,
          TraceHeaderLines(bench_.scenario(), bench_.chain(), bench_.target(), 1,
                           "dpc-polarimeter " + std::string(options.bench.lockstep ? "lockstep" : "real time")));
    }
    link_.SetLoopReports([this] { Turned(); }, [this](const char* phase) { return GuardPhase(phase); });
    for (const std::string& line : bus::DescribeShmCleanup(link_.participant().shm_cleanup())) {
      spdlog::info("{}", line);
    }
    spdlog::info("{}, {} controls, profiles {}, domain {}",
                 options.bench.lockstep ? "lockstep" : fmt::format("real time at {} Hz", options.bench.rate_hz),
                 bench_.control_count(), link_.participant().profiles_file(), common.domain_id);
  }

  /// A turn is a sample (or a failed reading, or 100 ms of a lockstep wait); with an instrument,
  /// one reading may take its connection (4 timeouts), the stream's start and the query.
  std::optional<double> LongestTurnS() const override {
    if (!instrument_) return 0.0;
    return 6.0 * instrument_->device().link.response_timeout_s + 0.1;
  }
  cli::Heartbeat GuardHeartbeat() const override {
    return {bus::OldestEventThreadTickNs, bus::kEventThreadStuckS, bus::kEventThreadWhat};
  }

  cli::ExitCode run() override {
    GuardPhase("its samples");
    TraceObserver observer(trace_.get(), this);
    const BenchReport report =
        instrument_ ? bench_.RunInstrument(&link_, instrument_.get(), &observer,
                                           [this](const std::string& why) {
                                             failures_.Log(spdlog::level::warn, "instrument", "no reading: " + why);
                                           })
                    : bench_.Run(&link_, &observer);
    if (trace_) trace_->Flush();
    const RunSummary& s = report.result.summary;
    spdlog::info("{}: {} samples ({} published) at {:.0f} Hz, {} overruns, {} rejected states; "
                 "error mean {:.3f}° p99 {:.3f}° max {:.3f}°",
                 report.stop_reason, report.samples, report.published, report.achieved_rate_hz,
                 report.overruns, link_.rejected_states(), s.error_deg.mean, s.error_deg.p99,
                 s.error_deg.max);
    const nlohmann::ordered_json latency = link_.LoopLatencyJson();
    if (const auto& loop = latency["sample_to_state_received"]; loop["count"].get<int64_t>() > 0) {
      spdlog::info("loop latency (sample published → state received, {} states): p50 {:.1f} µs, "
                   "p99 {:.1f} µs, p99.9 {:.1f} µs",
                   loop["count"].get<int64_t>(), loop["p50"].get<double>(), loop["p99"].get<double>(),
                   loop["p999"].get<double>());
    }
    if (options_.json) {
      nlohmann::ordered_json out = cli::RunReportJson(
          cli::DescribeRun(bench_.scenario(), bench_.chain(), bench_.target(), "bench"), report.result, {});
      out["bench"] = {{"mode", options_.bench.lockstep ? "lockstep" : "realtime"},
                      {"published", report.published},
                      {"overruns", report.overruns},
                      {"achieved_rate_hz", report.achieved_rate_hz},
                      {"rejected_states", link_.rejected_states()},
                      {"state_deadline_misses", link_.state_counters().deadline_misses.load()},
                      {"stop_reason", report.stop_reason},
                      {"loop_latency_us", latency}};
      if (instrument_) {
        const InstrumentPolarimeter::Counters& c = instrument_->counters();
        out["instrument"] = {{"name", instrument_->name()},         {"queries", c.queries},
                             {"readings", c.readings},              {"overtaken", c.overtaken},
                             {"timeouts", c.timeouts},
                             {"refused_replies", c.refused_replies}, {"connects", c.connects},
                             {"failed_connects", c.failed_connects}, {"failed_periods", report.failed_readings},
                             {"query_round_trip_us",
                              {{"p50", instrument_->query_times().Percentile(0.5)},
                               {"p99", instrument_->query_times().Percentile(0.99)}}}};
      }
      std::cout << out.dump() << std::endl;
    }
    const bool failed = options_.bench.lockstep && report.stop_reason != "end of scenario" &&
                        report.stop_reason != "stopped" && report.stop_reason != "stopped by signal";
    if (failed) {
      spdlog::error("{}", report.stop_reason);
      return cli::ExitCode::kRuntimeError;
    }
    return cli::ExitCode::kOk;
  }

 private:
  void OnStop() override { link_.Stop(); }
  void OnReloadRequested() override { link_.RequestReload(); }

  Options options_;
  BenchCore bench_;
  DdsBenchLink link_;
  std::unique_ptr<TraceWriter> trace_;
  std::unique_ptr<InstrumentPolarimeter> instrument_;  ///< a real polarimeter, if the scenario has one
  LogLimiter failures_;  ///< the instrument's failed readings, rate-limited with counts
};

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) {
  return dpc::services::ServiceMain<dpc::services::PolarimeterService>(
      argc, argv, "dpc-polarimeter: the simulated optical bench and its polarimeter");
}
