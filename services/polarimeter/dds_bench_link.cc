#include "dds_bench_link.h"

#include <algorithm>
#include <chrono>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "dpc/bench/clock.h"
#include "dpc/bus/message_conversion.h"

namespace dpc::services {

DdsBenchLink::DdsBenchLink(bus::ParticipantMaker maker, int control_count, const std::string& bench_id,
                           double lockstep_timeout_s, double latency_warmup_s, double summary_hz,
                           const TargetConfig& target)
    : bench_id_(bench_id),
      control_count_(control_count),
      lockstep_timeout_s_(lockstep_timeout_s),
      summary_hz_(summary_hz),
      maker_(std::move(maker)),
      participant_(maker_.Make()),
      summary_(target),
      latest_(WaveplateMotion::Still(ControlVector::Zero(control_count))),
      latency_(WallClockNs() + static_cast<int64_t>(latency_warmup_s * 1e9)) {
  if (summary_hz > 0) {
    summary_period_ns_ = static_cast<int64_t>(1e9 / summary_hz);
    next_summary_ns_ = MonotonicNs() + summary_period_ns_;
  }
  MakeEndpoints();
}

DdsBenchLink::~DdsBenchLink() { DeleteEndpoints(); }

void DdsBenchLink::MakeEndpoints() {
  writer_ = participant_->MakeWriter<msg::StokesSample>(bench_id_);
  if (summary_hz_ > 0) {
    try {
      summary_writer_ = participant_->MakeWriter<msg::BenchSummary>(bench_id_);
    } catch (const std::exception& e) {
      // Permissions signed before the topic existed: the bench runs, observers miss the summary.
      spdlog::warn("no dpc_bench_summary ({}); make-bench-pki.sh signs the permissions that grant it", e.what());
    }
  }
  // The bench's report counts the state topic's missed deadlines: this reader requests it.
  states_ = participant_->MakeReader<msg::WaveplateState>(
      bench_id_, [this](const msg::WaveplateState& state, const auto& info) { OnState(state, bus::SourceOf(info)); },
      bus::DeadlineWatch::kOn);
  targets_ = participant_->MakeReader<msg::Target>(
      bench_id_, [this](const msg::Target& target, const auto& info) { OnTarget(target, bus::SourceOf(info)); });
}

void DdsBenchLink::DeleteEndpoints() {
  states_.reset();
  targets_.reset();
  summary_writer_.reset();
  writer_.reset();
}

void DdsBenchLink::WriteSample(const BenchSample& sample) {
  bus::WriteSample(sample, bench_id_, &sample_message_);
  writer_->Write(sample_message_);
}

void DdsBenchLink::Publish(const BenchSample& sample) {
  // A SIGHUP, or a handshake stall: progress is a valid state of the driver's, which a stalled
  // handshake with it withholds.
  if (const auto cause = maker_.ReloadCause(reload_requested_.exchange(false), *participant_, MonotonicNs(),
                                            progress_ns_.load(std::memory_order_relaxed))) {
    maker_.Reload(&participant_, [this] { DeleteEndpoints(); }, [this] { MakeEndpoints(); }, *cause);
  }
  WriteSample(sample);
  if (!summary_writer_) return;
  const int64_t now_ns = MonotonicNs();
  BenchSummary summary;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    summary_.OnSample(sample);
    if (now_ns < next_summary_ns_) return;
    summary = summary_.Take(now_ns, WallClockNs());
  }
  next_summary_ns_ = std::max(next_summary_ns_ + summary_period_ns_, now_ns);  // no burst after a stall
  bus::WriteSummary(summary, bench_id_, &summary_message_);
  summary_writer_->Write(summary_message_);
}

void DdsBenchLink::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopped_ = true;
  }
  answered_.notify_all();
}

std::optional<ControlVector> DdsBenchLink::AwaitAnswer(const BenchSample& sample, std::string* why) {
  std::unique_lock<std::mutex> lock(mutex_);
  awaited_ = sample.sequence;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(lockstep_timeout_s_));
  while (!answer_) {
    turned_();
    if (stopped_) {
      *why = "stopped by signal";
      return std::nullopt;
    }
    // Re-publish now and then: the first samples go out before a controller has matched.
    if (answered_.wait_for(lock, std::chrono::milliseconds(100)) == std::cv_status::timeout && !answer_ &&
        !stopped_) {
      if (std::chrono::steady_clock::now() > deadline) {
        *why = fmt::format("no state answered sample {} within {} s (is a driver and a "
                           "controller running on this domain and bench id?)",
                           sample.sequence, lockstep_timeout_s_);
        return std::nullopt;
      }
      lock.unlock();
      BenchSample again = sample;
      again.publish_time_ns = WallClockNs();
      WriteSample(again);  // the same sample: the summary has it already
      lock.lock();
    }
  }
  ControlVector phi = std::move(*answer_);
  answer_.reset();
  return phi;
}

bool DdsBenchLink::TakeApplied(WaveplateMotion* motion) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!latest_fresh_) return false;
  *motion = latest_;  // ControlVector has fixed storage: copying allocates nothing
  latest_fresh_ = false;
  return true;
}

std::optional<TargetConfig> DdsBenchLink::TargetChange() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<TargetConfig> change;
  change.swap(target_change_);
  return change;
}

uint64_t DdsBenchLink::rejected_states() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rejected_states_;
}

nlohmann::ordered_json DdsBenchLink::LoopLatencyJson() {
  std::lock_guard<std::mutex> lock(mutex_);
  return latency_.Json();
}

bool DdsBenchLink::FromDriver(const SourceId& source, const char* what) {
  if (participant_->AcceptFrom(&driver_source_, source)) return true;
  log_.Log(spdlog::level::warn, std::string("foreign ") + what, driver_source_.Refusal(what, "driver"));
  return false;
}

void DdsBenchLink::OnState(const msg::WaveplateState& message, const SourceId& source) {
  const int64_t receive_wall_ns = WallClockNs();
  std::lock_guard<std::mutex> lock(mutex_);
  if (!FromDriver(source, "state")) {
    ++rejected_states_;
    return;
  }
  if (std::string reason = bus::ReadState(message, control_count_, &state_); !reason.empty()) {
    rejections_.Update(++rejected_states_, reason);
    return;
  }
  latency_.OnState(state_, receive_wall_ns);
  summary_.OnState(state_, receive_wall_ns);
  // One value per control: latest_ keeps its size, nothing allocates.
  latest_ = state_.motion;
  latest_fresh_ = true;
  progress_ns_.store(MonotonicNs(), std::memory_order_relaxed);
  if (awaited_ != 0 && state_.answers_sample == awaited_) {
    answer_ = latest_.phi;  // lockstep: the point (lockstep controllers send no rate)
    awaited_ = 0;
    answered_.notify_one();
  }
}

void DdsBenchLink::OnTarget(const msg::Target& message, const SourceId& source) {
  BenchTarget target;
  const std::string reason = bus::ReadTarget(message, &target);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!FromDriver(source, "target")) return;
  if (!reason.empty()) {
    log_.Log(spdlog::level::warn, "rejected target",
             fmt::format("rejected target revision {}: {}", message.revision(), reason));
    return;
  }
  if (target.revision > target_revision_) {
    target_revision_ = target.revision;
    target_change_ = target.target;
    summary_.OnTarget(target.target);
  }
}

}  // namespace dpc::services
