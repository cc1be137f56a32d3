#pragma once
// The simulated bench's view of the bus (BenchLink over Fast DDS): publishes the samples,
// collects the driver's states (checked at this edge, bus::ReadState) and the target.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "bench_core.h"
#include "dpc/bench/bench_summary.h"
#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/participant_maker.h"
#include "log_limiter.h"
#include "loop_latency.h"
#include "service_runtime.h"

namespace dpc::services {

class DdsBenchLink final : public BenchLink {
 public:
  /// On a participant `maker` makes (now, and again on RequestReload). Lockstep: gives up on a
  /// sample no state answers within `lockstep_timeout_s`. The loop latency counts samples
  /// published from `latency_warmup_s` on. Every 1/`summary_hz` s (0: never) a BenchSummary of
  /// what it saw goes to dpc_bench_summary, starting from `target`.
  DdsBenchLink(bus::ParticipantMaker maker, int control_count, const std::string& bench_id, double lockstep_timeout_s,
               double latency_warmup_s, double summary_hz, const TargetConfig& target);
  ~DdsBenchLink() override;

  void Publish(const BenchSample& sample) override;
  std::optional<ControlVector> AwaitAnswer(const BenchSample& sample, std::string* why) override;
  bool TakeApplied(WaveplateMotion* motion) override;
  std::optional<TargetConfig> TargetChange() override;
  /// Asked once per turn of the bench's real-time loops: a turn for the loop guard too.
  bool stop_requested() override {
    turned_();
    return stopped_.load(std::memory_order_relaxed);
  }
  /// The loop guard's reports (Service::Turned, Service::GuardPhase): each turn of the bench's
  /// loop (a sample, a failed reading, a lockstep wait's 100 ms) calls `turned`; a reload of
  /// the participant is named by `phase` while it runs (bus::ParticipantMaker::PhaseReport).
  void SetLoopReports(std::function<void()> turned, bus::ParticipantMaker::PhaseReport phase) {
    turned_ = std::move(turned);
    maker_.SetPhaseReport(std::move(phase));
  }

  /// Thread-safe: the bench stops at its next sample; a lockstep wait ends at once.
  void Stop();
  /// Thread-safe (SIGHUP): the next Publish makes the participant again, and a later one moves
  /// the endpoints to it (bus::ParticipantMaker::Reload: secured, once it has authenticated the
  /// peers); the bench's loop pauses while the new endpoints are matched.
  void RequestReload() { reload_requested_.store(true); }
  const bus::BusParticipant& participant() const { return *participant_; }

  uint64_t rejected_states() const;
  /// The loop latency seen in the states so far (see LoopLatencyRecorder).
  nlohmann::ordered_json LoopLatencyJson();
  const bus::ReaderCounters& state_counters() const { return states_->counters(); }

 private:
  /// Puts one sample on the bus (Publish, and AwaitAnswer's re-publications).
  void WriteSample(const BenchSample& sample);
  /// The endpoints on participant_ (on the bench's thread, without mutex_: the readers' callbacks
  /// take it).
  void MakeEndpoints();
  void DeleteEndpoints();
  void OnState(const msg::WaveplateState& message, const SourceId& source);
  void OnTarget(const msg::Target& message, const SourceId& source);
  /// Whether `source` is the bench's driver (SourceBinding); else logs the refusal. Under mutex_.
  bool FromDriver(const SourceId& source, const char* what);

  std::function<void()> turned_ = [] {};
  std::string bench_id_;
  int control_count_;
  double lockstep_timeout_s_;
  std::atomic<bool> stopped_{false};
  std::atomic<bool> reload_requested_{false};
  std::atomic<int64_t> progress_ns_{MonotonicNs()};  ///< the latest valid state of the driver's (start: none yet)
  double summary_hz_;
  bus::ParticipantMaker maker_;
  std::unique_ptr<bus::BusParticipant> participant_;  ///< replaced only by a reload (Publish)
  msg::StokesSample sample_message_;  ///< written in place (Publish runs on the bench's thread)
  std::unique_ptr<bus::Writer<msg::StokesSample>> writer_;
  // The summary: folded under mutex_, written on the bench's thread when due.
  std::unique_ptr<bus::Writer<msg::BenchSummary>> summary_writer_;  ///< null: no summaries
  int64_t summary_period_ns_ = 0;
  int64_t next_summary_ns_ = 0;
  BenchSummaryBuilder summary_;
  msg::BenchSummary summary_message_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> states_;
  std::unique_ptr<bus::Reader<msg::Target>> targets_;
  mutable std::mutex mutex_;
  SourceBinding driver_source_{kSourceReleaseNs};  ///< states and targets: the driver's participant
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
  LogLimiter log_;  ///< under mutex_
};

}  // namespace dpc::services
