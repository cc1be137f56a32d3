#pragma once
// What the bench did over one short period (the polarimeter publishes one per 1/--summary-hz s,
// topic dpc_bench_summary): for observers that must not read the bench's rate. A dashboard
// subscribed to every sample and state of a 10-kHz bench costs the bench two extra datagrams a
// sample; the summary costs it 20 a second.
//
// The polarimeter folds what it sees anyway (every sample it publishes, every state of its
// driver, the target) into a BenchSummaryBuilder and takes a summary when it is due.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"
#include "dpc/control/target.h"

namespace dpc {

/// At most this many S_in/S_out points per summary (spread evenly over its period).
inline constexpr size_t kMaxSummaryTrailPoints = 48;

struct BenchSummary {
  uint64_t sequence = 0;            ///< 1, 2, … per polarimeter run
  int64_t publish_time_ns = 0;      ///< wall clock
  double period_s = 0.0;            ///< since the previous summary
  uint64_t samples = 0;             ///< published in the period
  uint64_t last_sample = 0;         ///< the latest sample's sequence number (0: none yet)
  StokesVector s_in = StokesVector::UnitX();   ///< the latest sample's (unit)
  StokesVector s_out = StokesVector::UnitX();
  std::vector<std::array<double, 6>> trail;    ///< S_in, S_out per point; ≤ kMaxSummaryTrailPoints
  std::optional<double> error_mean_deg;        ///< S_out to the target over the period
  double error_max_deg = 0.0;
  uint64_t latencies = 0;           ///< loop latencies measured in the period
  double latency_p50_us = 0.0;      ///< sample published → state answering it received
  double latency_p90_us = 0.0;
  double latency_p99_us = 0.0;
  double latency_max_us = 0.0;
  std::optional<DriverState> state; ///< the driver's latest state (its motion's φ, mode, …)
};

class BenchSummaryBuilder {
 public:
  explicit BenchSummaryBuilder(const TargetConfig& target);

  void OnSample(const BenchSample& sample);
  /// A valid state of the bench's driver, received at `receive_wall_ns`.
  void OnState(const DriverState& state, int64_t receive_wall_ns);
  void OnTarget(const TargetConfig& target);

  /// The summary of the period since the previous one (`now_ns`: a monotonic clock; the first
  /// period starts at the builder's first call); starts a new period.
  BenchSummary Take(int64_t now_ns, int64_t wall_ns);

 private:
  Target target_;
  std::optional<int64_t> last_take_ns_;
  uint64_t sequence_ = 0;
  uint64_t samples_ = 0;
  std::optional<BenchSample> last_sample_;
  uint64_t errors_ = 0;
  double error_sum_deg_ = 0.0;
  double error_max_deg_ = 0.0;
  std::vector<std::array<double, 6>> trail_;
  int64_t trail_stride_ = 1;
  int64_t trail_counter_ = 0;
  std::vector<double> latencies_us_;
  int64_t latency_stride_ = 1;
  int64_t latency_counter_ = 0;
  uint64_t last_latency_sample_ = 0;
  std::optional<DriverState> state_;
};

/// Keeps every `stride`-th value pushed and at most `2·capacity` values: when full, every other
/// one goes and the stride doubles. What the summary uses to stay bounded at any rate.
template <class T>
void PushDecimated(std::vector<T>* values, const T& value, size_t capacity, int64_t* stride, int64_t* counter) {
  if ((*counter)++ % *stride != 0) return;
  values->push_back(value);
  if (values->size() >= 2 * capacity) {
    size_t kept = 0;
    for (size_t i = 0; i < values->size(); i += 2) (*values)[kept++] = (*values)[i];
    values->resize(kept);
    *stride *= 2;
  }
}

}  // namespace dpc
