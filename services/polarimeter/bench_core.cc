#include "bench_core.h"

#include <sys/prctl.h>

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "dpc/bench/clock.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/sim/delay_line.h"
#include "dpc/sim/simulation_run.h"

namespace dpc::services {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

int64_t SecondsToNs(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

}  // namespace

BenchCore::BenchCore(ScenarioConfig scenario, BenchSettings settings)
    : scenario_(std::move(scenario)), settings_(std::move(settings)) {
  if (!settings_.lockstep) {
    // Real time: the input runs at the polarimeter's rate; one sample of delay is the least the
    // validation accepts (the real delay is the loop's).
    scenario_.simulation.sample_rate_hz = settings_.rate_hz;
    scenario_.simulation.delay_s = 1.0 / settings_.rate_hz;
    scenario_.controller.activation_s = 0.0;
    scenario_.controller.dither.reset_duration_s =
        std::max(scenario_.controller.dither.reset_duration_s, 1.0 / settings_.rate_hz);
    // Until stopped: validate as a long run (the scenario's duration and settle_samples were
    // written for its own rate, e.g. 1 s, which a slow polarimeter would not even fill).
    scenario_.simulation.duration_s = settings_.duration_s > 0.0 ? settings_.duration_s : 1e6;
    scenario_.simulation.settle_samples = 0;  // real time settles by --settle-s instead
  }
  ValidateScenario(scenario_);
  chain_ = std::make_unique<WaveplateChain>(BuildChain(scenario_.stages));
  target_ = std::make_unique<Target>(BuildTarget(scenario_.target));
  initial_phi_ = BuildInitialPhi(scenario_.controller, chain_->control_count());
}

BenchCore::~BenchCore() = default;

BenchSample BenchCore::MakeSample(uint64_t sequence, int64_t sample_time_ns, const StokesVector& s_in,
                                  const StokesVector& s_out) const {
  BenchSample sample;
  sample.sequence = sequence;
  sample.time_ns = sample_time_ns;
  sample.s_in = s_in;
  sample.s_out = s_out;
  sample.lockstep = settings_.lockstep;
  sample.publish_time_ns = WallClockNs();
  return sample;
}

BenchReport BenchCore::Run(BenchLink* link, SimulationObserver* observer) {
  return settings_.lockstep ? RunLockstep(link, observer) : RunRealTime(link, observer);
}

BenchReport BenchCore::RunLockstep(BenchLink* link, SimulationObserver* observer) {
  const WaveplateChain& chain = *chain_;
  const int64_t total = TotalSamples(scenario_.simulation);
  const int64_t delay = DelaySamples(scenario_.simulation);
  const double dt_s = 1.0 / scenario_.simulation.sample_rate_hz;
  const double activation = scenario_.controller.activation_s * scenario_.simulation.sample_rate_hz;
  // As ClosedLoopSimulator: the first sample at or after activation_s.
  const int64_t activation_sample =
      static_cast<int64_t>(std::ceil(activation - 1e-9 * std::max(1.0, activation)));
  SimulationRun run(scenario_, *target_, chain.control_count(), total, observer, 1);
  ChainPose initial_pose;
  chain.ComputePose(initial_phi_, &initial_pose);
  DelayLine<ChainPose> line(delay, initial_pose);

  BenchReport report;
  int64_t slot = 0;
  int64_t k = 0;
  ControlVector latest = initial_phi_;
  for (; k < total; ++k, slot = line.Next(slot)) {
    const double t_s = static_cast<double>(k) * dt_s;
    const StokesVector& s_in = run.input.Next();
    const ChainPose& applied = line.at(slot);
    const StokesVector s_out = chain.Output(applied, s_in);
    bool issued = false;
    if (k >= activation_sample) {
      run.statistics.AddSample(t_s, s_out, applied.phi);
      const StokesVector in_measured = run.input_polarimeter.Measure(s_in);
      const StokesVector out_measured = run.output_polarimeter.Measure(s_out);
      if (run.TakesSample()) {
        run.observer().OnSample(SampleView{k, t_s, s_in, s_out, applied.phi,
                                           target_->DistanceRad(s_out) * kRadToDeg});
      }
      const BenchSample sample =
          MakeSample(static_cast<uint64_t>(k + 1), SecondsToNs(t_s), in_measured, out_measured);
      link->Publish(sample);
      ++report.published;
      std::string why;
      const std::optional<ControlVector> answer = link->AwaitAnswer(sample, &why);
      if (!answer) {
        report.stop_reason = why;
        line.Close(slot, false);
        break;
      }
      // The state's φ acts from sample k + D, as a command issued at k in the simulator.
      chain.ComputePose(*answer, &line.issue(slot));
      latest = *answer;
      issued = true;
    } else if (run.TakesSample()) {
      run.observer().OnSample(SampleView{k, t_s, s_in, s_out, applied.phi,
                                         target_->DistanceRad(s_out) * kRadToDeg});
    }
    line.Close(slot, issued);
    if (((k + 1) & 1023) == 0) {
      if (settings_.lockstep_progress) settings_.lockstep_progress(k + 1, total);
      if (!run.EndBlock(k + 1)) {
        report.stop_reason = "stopped";
        ++k;
        break;
      }
    }
  }
  report.samples = k;
  report.result = run.Finish(k, 0, latest);
  report.achieved_rate_hz = report.result.samples_per_s;
  if (report.stop_reason.empty()) report.stop_reason = "end of scenario";
  return report;
}

BenchReport BenchCore::RunRealTime(BenchLink* link, SimulationObserver* observer) {
  // Timer slack of 1 ns: the kernel's default 50 µs would blur a 50 µs period.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  const WaveplateChain& chain = *chain_;
  const double dt_s = 1.0 / settings_.rate_hz;
  const int64_t period_ns = SecondsToNs(dt_s);
  const int64_t total = settings_.duration_s > 0.0
                            ? static_cast<int64_t>(std::llround(settings_.duration_s * settings_.rate_hz))
                            : INT64_MAX;
  SimulationRun run(scenario_, *target_, chain.control_count(), total, observer, 1);
  std::unique_ptr<Target> target = std::make_unique<Target>(*target_);
  auto statistics = std::make_unique<RunStatistics>(*target, chain.control_count(), 0.0,
                                                    scenario_.simulation.lock_threshold_deg,
                                                    std::nullopt, settings_.settle_s);
  double statistics_origin_s = 0.0;
  ChainPose pose;
  ControlVector phi = initial_phi_;
  ControlVector phi_now = initial_phi_;
  // The latest state's motion, copied in without allocating (its vectors keep their size).
  WaveplateMotion motion = WaveplateMotion::Still(initial_phi_);
  chain.ComputePose(phi, &pose);

  BenchReport report;
  const int64_t start_ns = MonotonicNs();
  int64_t next_ns = start_ns;
  int64_t k = 0;
  for (; k < total; ++k) {
    if (link->stop_requested()) {
      report.stop_reason = "stopped";
      break;
    }
    SleepUntilMonotonicNs(next_ns);
    const int64_t now_ns = MonotonicNs();
    if (now_ns - next_ns > period_ns) {
      // Came late by more than a period: count it and do not try to catch up in a burst.
      report.overruns += (now_ns - next_ns) / period_ns;
      next_ns = now_ns;
    }
    next_ns += period_ns;
    if (auto change = link->TargetChange()) {
      target = std::make_unique<Target>(BuildTarget(*change));
      statistics = std::make_unique<RunStatistics>(*target, chain.control_count(), 0.0,
                                                   scenario_.simulation.lock_threshold_deg,
                                                   std::nullopt, settings_.settle_s);
      statistics_origin_s = static_cast<double>(k) * dt_s;
    }
    const double t_s = static_cast<double>(k) * dt_s;
    const int64_t t_ns = SecondsToNs(t_s);
    if (link->TakeApplied(&motion) || motion.moving) {
      motion.At(t_ns, &phi_now);
      if (phi_now != phi) {
        phi = phi_now;
        chain.ComputePose(phi, &pose);
      }
    }
    const StokesVector& s_in = run.input.Next();
    const StokesVector s_out = chain.Output(pose, s_in);
    statistics->AddSample(t_s - statistics_origin_s, s_out, pose.phi);
    if (run.TakesSample()) {
      run.observer().OnSample(SampleView{k, t_s, s_in, s_out, pose.phi, target->DistanceRad(s_out) * kRadToDeg});
    }
    link->Publish(MakeSample(static_cast<uint64_t>(k + 1), t_ns,
                             run.input_polarimeter.Measure(s_in), run.output_polarimeter.Measure(s_out)));
    ++report.published;
    if (((k + 1) & 1023) == 0 && !run.EndBlock(k + 1)) {
      report.stop_reason = "stopped";
      ++k;
      break;
    }
  }
  const double wall_s = static_cast<double>(MonotonicNs() - start_ns) * 1e-9;
  report.samples = k;
  report.result.summary = statistics->Summarize(k, 0);
  report.result.wall_time_s = wall_s;
  report.result.samples_per_s = wall_s > 0.0 ? static_cast<double>(k) / wall_s : 0.0;
  report.result.final_phi = phi;
  report.achieved_rate_hz = report.result.samples_per_s;
  if (report.stop_reason.empty()) report.stop_reason = "end of --run-s";
  return report;
}

BenchReport BenchCore::RunInstrument(BenchLink* link, InstrumentPolarimeter* polarimeter, SimulationObserver* observer,
                                     const std::function<void(const std::string&)>& on_failure) {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  const WaveplateChain& chain = *chain_;
  const int64_t period_ns = SecondsToNs(1.0 / settings_.rate_hz);
  const int64_t run_ns = settings_.duration_s > 0.0 ? SecondsToNs(settings_.duration_s) : INT64_MAX;
  std::unique_ptr<Target> target = std::make_unique<Target>(*target_);
  auto statistics = std::make_unique<RunStatistics>(*target, chain.control_count(), 0.0,
                                                    scenario_.simulation.lock_threshold_deg, std::nullopt,
                                                    settings_.settle_s);
  double statistics_origin_s = 0.0;
  ChainPose pose;
  ControlVector phi = initial_phi_;
  ControlVector phi_now = initial_phi_;
  WaveplateMotion motion = WaveplateMotion::Still(initial_phi_);
  chain.ComputePose(phi, &pose);

  BenchReport report;
  const int64_t start_ns = MonotonicNs();
  int64_t next_ns = start_ns;
  uint64_t sequence = 0;
  // Stream mode: the instrument's lines pace the loop (Measure waits for the next one); a
  // failed reading waits a period before the next attempt, so a lost link never spins.
  const bool stream = polarimeter->device().stream;
  bool failed = false;
  while (true) {
    if (link->stop_requested()) {
      report.stop_reason = "stopped";
      break;
    }
    if (!stream || failed) SleepUntilMonotonicNs(next_ns);
    if (MonotonicNs() - start_ns >= run_ns) break;
    const int64_t now_ns = MonotonicNs();
    if (stream) {
      next_ns = now_ns;
    } else if (now_ns - next_ns > period_ns) {
      report.overruns += (now_ns - next_ns) / period_ns;
      next_ns = now_ns;
    }
    next_ns += period_ns;
    ++report.samples;
    std::string why;
    const std::optional<PolarimeterReading> reading = polarimeter->Measure(now_ns, &why);
    failed = !reading;
    if (!reading) {
      ++report.failed_readings;
      on_failure(why);
      continue;
    }
    const int64_t t_ns = reading->reply_ns - start_ns;
    const double t_s = static_cast<double>(t_ns) * 1e-9;
    if (auto change = link->TargetChange()) {
      target = std::make_unique<Target>(BuildTarget(*change));
      statistics = std::make_unique<RunStatistics>(*target, chain.control_count(), 0.0,
                                                   scenario_.simulation.lock_threshold_deg, std::nullopt,
                                                   settings_.settle_s);
      statistics_origin_s = t_s;
    }
    if (link->TakeApplied(&motion) || motion.moving) {
      motion.At(t_ns, &phi_now);
      if (phi_now != phi) {
        phi = phi_now;
        chain.ComputePose(phi, &pose);
      }
    }
    // What the instrument does not measure, from the model at the applied φ.
    const StokesVector s_in = reading->s_in ? *reading->s_in : StokesVector(chain.MuellerMatrix(pose).transpose() * *reading->s_out);
    const StokesVector s_out = reading->s_out ? *reading->s_out : chain.Output(pose, s_in);
    if (t_s >= statistics_origin_s) statistics->AddSample(t_s - statistics_origin_s, s_out, pose.phi);
    if (observer != nullptr && observer->wants_samples()) {
      observer->OnSample(SampleView{static_cast<int64_t>(sequence), t_s, s_in, s_out, pose.phi,
                                    target->DistanceRad(s_out) * kRadToDeg});
    }
    BenchSample sample = MakeSample(++sequence, t_ns, s_in, s_out);
    sample.optical_power_w = reading->power_w;
    link->Publish(sample);
    ++report.published;
  }
  const double wall_s = static_cast<double>(MonotonicNs() - start_ns) * 1e-9;
  report.result.summary = statistics->Summarize(static_cast<int64_t>(sequence), 0);
  report.result.wall_time_s = wall_s;
  report.result.samples_per_s = wall_s > 0.0 ? static_cast<double>(sequence) / wall_s : 0.0;
  report.result.final_phi = phi;
  report.achieved_rate_hz = report.result.samples_per_s;
  if (report.stop_reason.empty()) report.stop_reason = "end of --run-s";
  return report;
}

}  // namespace dpc::services
