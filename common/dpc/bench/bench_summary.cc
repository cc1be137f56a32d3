#include "dpc/bench/bench_summary.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "dpc/config/scenario_builders.h"

namespace dpc {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr size_t kMaxLatencies = 4096;

/// The value at quantile q of `values` (nearest rank), found by partial ordering (O(n): this
/// runs on the bench's real-time thread; a full sort of each period is not needed). Reorders.
double Quantile(std::vector<double>* values, double q) {
  if (values->empty()) return 0.0;
  const auto rank = static_cast<size_t>(std::ceil(q * static_cast<double>(values->size())));
  const auto nth = values->begin() + static_cast<std::ptrdiff_t>(std::min(values->size() - 1, rank == 0 ? 0 : rank - 1));
  std::nth_element(values->begin(), nth, values->end());
  return *nth;
}

}  // namespace

BenchSummaryBuilder::BenchSummaryBuilder(const TargetConfig& target) : target_(BuildTarget(target)) {
  trail_.reserve(2 * kMaxSummaryTrailPoints);
  latencies_us_.reserve(2 * kMaxLatencies);
}

void BenchSummaryBuilder::OnSample(const BenchSample& sample) {
  ++samples_;
  last_sample_ = sample;
  PushDecimated(&trail_,
                std::array<double, 6>{sample.s_in.x(), sample.s_in.y(), sample.s_in.z(), sample.s_out.x(),
                                      sample.s_out.y(), sample.s_out.z()},
                kMaxSummaryTrailPoints, &trail_stride_, &trail_counter_);
  const double error_deg = target_.DistanceRad(sample.s_out) * kDegPerRad;
  if (!std::isfinite(error_deg)) return;
  ++errors_;
  error_sum_deg_ += error_deg;
  error_max_deg_ = errors_ == 1 ? error_deg : std::max(error_max_deg_, error_deg);
}

void BenchSummaryBuilder::OnState(const DriverState& state, int64_t receive_wall_ns) {
  // The loop latency of each newly answered sample: published → the state answering it here.
  if (state.answers_sample != 0 && state.answers_sample != last_latency_sample_ && state.sample_publish_time_ns > 0 &&
      receive_wall_ns >= state.sample_publish_time_ns) {
    last_latency_sample_ = state.answers_sample;
    const double latency_us = static_cast<double>(receive_wall_ns - state.sample_publish_time_ns) / 1e3;
    if (latency_us < 1e7) PushDecimated(&latencies_us_, latency_us, kMaxLatencies, &latency_stride_, &latency_counter_);
  }
  state_ = state;
}

void BenchSummaryBuilder::OnTarget(const TargetConfig& target) { target_ = BuildTarget(target); }

BenchSummary BenchSummaryBuilder::Take(int64_t now_ns, int64_t wall_ns) {
  BenchSummary s;
  s.sequence = ++sequence_;
  s.publish_time_ns = wall_ns;
  s.period_s = last_take_ns_ ? static_cast<double>(now_ns - *last_take_ns_) / 1e9 : 0.0;
  last_take_ns_ = now_ns;
  s.samples = samples_;
  if (last_sample_) {
    s.last_sample = last_sample_->sequence;
    s.s_in = last_sample_->s_in;
    s.s_out = last_sample_->s_out;
  }
  const size_t step = trail_.size() > kMaxSummaryTrailPoints ? 2 : 1;
  for (size_t i = 0; i < trail_.size(); i += step) s.trail.push_back(trail_[i]);
  if (errors_ > 0) {
    s.error_mean_deg = error_sum_deg_ / static_cast<double>(errors_);
    s.error_max_deg = error_max_deg_;
  }
  if (!latencies_us_.empty()) {
    s.latencies = latencies_us_.size();
    s.latency_max_us = *std::max_element(latencies_us_.begin(), latencies_us_.end());
    s.latency_p50_us = Quantile(&latencies_us_, 0.50);
    s.latency_p90_us = Quantile(&latencies_us_, 0.90);
    s.latency_p99_us = Quantile(&latencies_us_, 0.99);
  }
  s.state = state_;

  // A new period; the strides relax when the rate fell.
  if (trail_.size() < kMaxSummaryTrailPoints / 2 && trail_stride_ > 1) trail_stride_ /= 2;
  if (latencies_us_.size() < kMaxLatencies / 2 && latency_stride_ > 1) latency_stride_ /= 2;
  trail_.clear();
  trail_counter_ = 0;
  latencies_us_.clear();
  latency_counter_ = 0;
  samples_ = 0;
  errors_ = 0;
  error_sum_deg_ = 0.0;
  error_max_deg_ = 0.0;
  return s;
}

}  // namespace dpc
