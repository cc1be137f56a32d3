#include "loop_latency.h"

#include <cmath>

namespace dpc::services {
namespace {

constexpr double kMaxSpanUs = 10e6;

nlohmann::ordered_json Summary(const LogHistogram& h) {
  nlohmann::ordered_json out;
  out["count"] = h.count();
  if (h.count() == 0) {
    out["p50"] = out["p99"] = out["p999"] = out["max"] = nullptr;
    return out;
  }
  out["p50"] = h.Percentile(50.0);
  out["p99"] = h.Percentile(99.0);
  out["p999"] = h.Percentile(99.9);
  out["max"] = h.max();
  return out;
}

}  // namespace

// 0.01 µs … 10 s with 256 bins per octave: 0.4 % resolution, ~8 k bins, 64 KiB each.
LoopLatencyRecorder::LoopLatencyRecorder(int64_t since_wall_ns)
    : since_wall_ns_(since_wall_ns),
      to_driver_us_(1e-2, kMaxSpanUs, 8),
      to_state_published_us_(1e-2, kMaxSpanUs, 8),
      to_state_received_us_(1e-2, kMaxSpanUs, 8) {}

void LoopLatencyRecorder::OnState(const DriverState& state, int64_t receive_wall_ns) {
  if (state.answers_sample <= last_answered_ || state.sample_publish_time_ns <= 0 ||
      state.sample_publish_time_ns < since_wall_ns_) {
    return;
  }
  last_answered_ = state.answers_sample;
  const int64_t origin_ns = state.sample_publish_time_ns;
  // A peer's fields are arbitrary: a difference that does not fit an int64 is implausible (NaN).
  const auto span_us = [origin_ns](int64_t t_ns) {
    int64_t span_ns;
    return __builtin_sub_overflow(t_ns, origin_ns, &span_ns) ? NAN : static_cast<double>(span_ns) * 1e-3;
  };
  const double to_driver_us = span_us(state.command_receive_time_ns);
  const double to_published_us = span_us(state.publish_time_ns);
  const double to_received_us = span_us(receive_wall_ns);
  auto plausible = [](double us) { return us >= 0.0 && us <= kMaxSpanUs; };
  if (!plausible(to_driver_us) || !plausible(to_published_us) || !plausible(to_received_us)) {
    ++implausible_;
    return;
  }
  to_driver_us_.Add(to_driver_us);
  to_state_published_us_.Add(to_published_us);
  to_state_received_us_.Add(to_received_us);
}

nlohmann::ordered_json LoopLatencyRecorder::Json() const {
  nlohmann::ordered_json out;
  out["sample_to_command_at_driver"] = Summary(to_driver_us_);
  out["sample_to_state_published"] = Summary(to_state_published_us_);
  out["sample_to_state_received"] = Summary(to_state_received_us_);
  out["implausible"] = implausible_;
  return out;
}

}  // namespace dpc::services
