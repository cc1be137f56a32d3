// dpc-polarimeter: the simulated optical bench and its polarimeter. Publishes a Stokes sample
// per period (real time) or per simulated sample, waiting for the answering state (lockstep).
//
//   dpc-polarimeter [SCENARIO] [--rate-hz 10000] [--run-s 0]          real time until stopped
//   dpc-polarimeter SCENARIO --lockstep [--trace FILE] [--json]       reproduces `dpc sim`

#include <condition_variable>
#include <iostream>
#include <mutex>

#include <spdlog/spdlog.h>

#include "bench_core.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bench/clock.h"
#include "dpc/config/scenario_error.h"
#include "dpc/sim/trace_writer.h"
#include "dpc/cli/run_report.h"
#include "loop_latency.h"
#include "service_runtime.h"

namespace dpc::services {
namespace {

/// The bench's view of the bus: publishes samples, collects states and targets.
class DdsBenchLink final : public BenchLink {
 public:
  DdsBenchLink(bus::BusParticipant* participant, const BenchCore* bench, const std::string& bench_id,
               ShutdownSignals* signals, double lockstep_timeout_s, double latency_warmup_s)
      : bench_id_(bench_id),
        control_count_(bench->control_count()),
        signals_(signals),
        lockstep_timeout_s_(lockstep_timeout_s),
        latest_(WaveplateMotion::Still(ControlVector::Zero(bench->control_count()))),
        latency_(WallClockNs() + static_cast<int64_t>(latency_warmup_s * 1e9)) {
    writer_ = participant->MakeWriter<msg::StokesSample>();
    states_ = participant->MakeReader<msg::WaveplateState>(
        bench_id, [this](const msg::WaveplateState& state, const auto&) { OnState(state); });
    targets_ = participant->MakeReader<msg::Target>(
        bench_id, [this](const msg::Target& target, const auto&) { OnTarget(target); });
  }
  ~DdsBenchLink() override {
    states_.reset();
    targets_.reset();
  }

  void Publish(const BenchSample& sample) override {
    bus::WriteSample(sample, bench_id_, &sample_message_);
    writer_->Write(sample_message_);
  }

  std::optional<ControlVector> AwaitAnswer(const BenchSample& sample, std::string* why) override {
    std::unique_lock<std::mutex> lock(mutex_);
    awaited_ = sample.sequence;
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(lockstep_timeout_s_));
    while (!answer_) {
      // Re-publish now and then: the first samples go out before a controller has matched.
      if (answered_.wait_for(lock, std::chrono::milliseconds(100)) == std::cv_status::timeout && !answer_) {
        lock.unlock();
        if (signals_->Wait(std::chrono::milliseconds(0))) {
          *why = "stopped by signal";
          return std::nullopt;
        }
        if (std::chrono::steady_clock::now() > deadline) {
          *why = fmt::format("no state answered sample {} within {} s (is a driver and a "
                             "controller running on this domain and bench id?)",
                             sample.sequence, lockstep_timeout_s_);
          return std::nullopt;
        }
        BenchSample again = sample;
        again.publish_time_ns = WallClockNs();
        Publish(again);
        lock.lock();
      }
    }
    ControlVector phi = std::move(*answer_);
    answer_.reset();
    return phi;
  }

  bool TakeApplied(WaveplateMotion* motion) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!latest_fresh_) return false;
    *motion = latest_;  // ControlVector has fixed storage: copying allocates nothing
    latest_fresh_ = false;
    return true;
  }
  std::optional<TargetConfig> TargetChange() override {
    std::lock_guard<std::mutex> lock(mutex_);
    std::optional<TargetConfig> change;
    change.swap(target_change_);
    return change;
  }
  // Polls for SIGINT/SIGTERM: requested() alone only reports what an earlier Wait collected,
  // and the real-time loop otherwise calls Wait only every 2^20 samples.
  bool stop_requested() override {
    // One sigtimedwait every 64 calls (≤ 64 ms at 1 kHz, 3 ms at 20 kHz), not one per sample.
    if ((++stop_polls_ & 63) != 0) return signals_->requested();
    return signals_->Wait(std::chrono::milliseconds(0));
  }

  uint64_t rejected_states() const { return rejected_states_; }
  /// The loop latency seen in the states so far (see LoopLatencyRecorder).
  nlohmann::ordered_json LoopLatencyJson() {
    std::lock_guard<std::mutex> lock(mutex_);
    return latency_.Json();
  }
  const bus::ReaderCounters& state_counters() const { return states_->counters(); }

 private:
  void OnState(const msg::WaveplateState& message) {
    const int64_t receive_wall_ns = WallClockNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::string reason = bus::ReadState(message, control_count_, &state_); !reason.empty()) {
      rejections_.Update(++rejected_states_, reason);
      return;
    }
    latency_.OnState(state_, receive_wall_ns);
    // One value per control: latest_ keeps its size, nothing allocates.
    latest_ = state_.motion;
    latest_fresh_ = true;
    if (awaited_ != 0 && state_.answers_sample == awaited_) {
      answer_ = latest_.phi;  // lockstep: the point (lockstep controllers send no rate)
      awaited_ = 0;
      answered_.notify_one();
    }
  }
  void OnTarget(const msg::Target& message) {
    BenchTarget target;
    if (std::string reason = bus::ReadTarget(message, &target); !reason.empty()) {
      spdlog::warn("rejected target revision {}: {}", message.revision(), reason);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (target.revision > target_revision_) {
      target_revision_ = target.revision;
      target_change_ = target.target;
    }
  }

  std::string bench_id_;
  int control_count_;
  msg::StokesSample sample_message_;  ///< written in place (Publish runs on the bench's thread)
  ShutdownSignals* signals_;
  double lockstep_timeout_s_;
  std::unique_ptr<bus::Writer<msg::StokesSample>> writer_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> states_;
  std::unique_ptr<bus::Reader<msg::Target>> targets_;
  std::mutex mutex_;
  std::condition_variable answered_;
  uint64_t awaited_ = 0;
  std::optional<ControlVector> answer_;
  WaveplateMotion latest_;      ///< the latest valid state's motion (one value per control)
  DriverState state_;           ///< read into in place, under mutex_
  bool latest_fresh_ = false;   ///< latest_ arrived since the last TakeApplied
  std::optional<TargetConfig> target_change_;
  uint64_t target_revision_ = 1;  // revision 1 is the scenario's target, the bench's own
  uint64_t rejected_states_ = 0;
  LoopLatencyRecorder latency_;  ///< this run's samples, after the warm-up
  RejectionLog rejections_{"rejected state"};
  uint64_t stop_polls_ = 0;
};

class TraceObserver final : public SimulationObserver {
 public:
  TraceObserver(TraceWriter* trace, ShutdownSignals* signals) : trace_(trace), signals_(signals) {}
  void OnSample(const SampleView& s) override {
    trace_->Write(s.t_s, s.s_in, s.s_out, s.error_deg, s.phi_applied);
  }
  bool wants_samples() const override { return trace_ != nullptr; }
  bool OnProgress(int64_t, int64_t) override { return !signals_->Wait(std::chrono::milliseconds(0)); }

 private:
  TraceWriter* trace_;
  ShutdownSignals* signals_;
};

int Run(int argc, char** argv) {
  ShutdownSignals signals;
  CLI::App app{"dpc-polarimeter: the simulated optical bench and its polarimeter"};
  CommonOptions common;
  AddCommonOptions(app, &common);
  BenchSettings settings;
  app.add_flag("--lockstep", settings.lockstep,
               "Simulated time: wait for the state answering each sample (reproduces dpc sim)");
  app.add_option("--rate-hz", settings.rate_hz, "Real time: samples per second")
      ->check(CLI::Range(1.0, 20000.0))->capture_default_str();
  app.add_option("--run-s", settings.duration_s, "Real time: stop after this long (0: until stopped)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--settle-s", settings.settle_s,
                 "Real time: error statistics from this long after the first lock, the loop "
                 "latency (bench.loop_latency_us) from this long after the start")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  double lockstep_timeout_s = 10.0;
  app.add_option("--lockstep-timeout-s", lockstep_timeout_s,
                 "Lockstep: give up when no state answers a sample for this long")
      ->check(CLI::Range(0.1, 3600.0))->capture_default_str();
  std::string trace_path;
  app.add_option("--trace", trace_path, "Write every sample to this CSV trace (dpc sim's format)");
  bool json = false;
  app.add_flag("--json", json, "Print the run's summary as one JSON object (dpc sim's fields)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  SetUpLogging("polarimeter", common);

  std::unique_ptr<BenchCore> bench;
  try {
    bench = std::make_unique<BenchCore>(LoadServiceScenario(common), settings);
  } catch (const ScenarioError& e) {
    spdlog::error("{}", DescribeError(e, common));
    return cli::ToInt(cli::ExitCode::kInvalidInput);
  }

  try {
    std::unique_ptr<TraceWriter> trace;
    if (!trace_path.empty()) {
      std::vector<std::string> names;
      for (const auto& c : bench->chain().controls()) names.push_back(c.name);
      trace = std::make_unique<TraceWriter>(
          trace_path, names, std::vector<std::string>{"dpc-polarimeter " + std::string(settings.lockstep ? "lockstep" : "real time")});
    }
    TraceObserver observer(trace.get(), &signals);
    bus::BusParticipant participant({common.domain_id, "dpc-polarimeter/" + common.bench_id});
    // The loop latency is counted, like the error, once the loop has settled: in real time
    // from --settle-s into the run (the first samples meet a controller re-joining and
    // processes touching fresh pages: single stalls of several ms); in lockstep from the start.
    DdsBenchLink link(&participant, bench.get(), common.bench_id, &signals, lockstep_timeout_s,
                      settings.lockstep ? 0.0 : settings.settle_s);
    spdlog::info("{}, {} controls, profiles {}, domain {}",
                 settings.lockstep ? "lockstep" : fmt::format("real time at {} Hz", settings.rate_hz),
                 bench->control_count(), participant.profiles_file(), common.domain_id);
    const BenchReport report = bench->Run(&link, &observer);
    if (trace) trace->Flush();
    const RunSummary& s = report.result.summary;
    spdlog::info("{}: {} samples ({} published) at {:.0f} Hz, {} overruns, {} rejected states; "
                 "error mean {:.3f}° p99 {:.3f}° max {:.3f}°",
                 report.stop_reason, report.samples, report.published, report.achieved_rate_hz,
                 report.overruns, link.rejected_states(), s.error_deg.mean, s.error_deg.p99,
                 s.error_deg.max);
    const nlohmann::ordered_json latency = link.LoopLatencyJson();
    if (const auto& loop = latency["sample_to_state_received"]; loop["count"].get<int64_t>() > 0) {
      spdlog::info("loop latency (sample published → state received, {} states): p50 {:.1f} µs, "
                   "p99 {:.1f} µs, p99.9 {:.1f} µs",
                   loop["count"].get<int64_t>(), loop["p50"].get<double>(), loop["p99"].get<double>(),
                   loop["p999"].get<double>());
    }
    if (json) {
      nlohmann::ordered_json out = cli::RunReportJson(
          cli::DescribeRun(bench->scenario(), bench->chain(), bench->target(), "bench"), report.result, {});
      out["bench"] = {{"mode", settings.lockstep ? "lockstep" : "realtime"},
                      {"published", report.published},
                      {"overruns", report.overruns},
                      {"achieved_rate_hz", report.achieved_rate_hz},
                      {"rejected_states", link.rejected_states()},
                      {"state_deadline_misses", link.state_counters().deadline_misses.load()},
                      {"stop_reason", report.stop_reason},
                      {"loop_latency_us", latency}};
      std::cout << out.dump() << std::endl;
    }
    const bool failed = settings.lockstep && report.stop_reason != "end of scenario" &&
                        report.stop_reason != "stopped" && report.stop_reason != "stopped by signal";
    if (failed) {
      spdlog::error("{}", report.stop_reason);
      return cli::ToInt(cli::ExitCode::kRuntimeError);
    }
  } catch (const bus::BusError& e) {
    spdlog::error("{}", e.what());
    return cli::ToInt(cli::ExitCode::kRuntimeError);
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return cli::ToInt(cli::ExitCode::kRuntimeError);
  }
  return cli::ToInt(cli::ExitCode::kOk);
}

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) { return dpc::services::Run(argc, argv); }
