#pragma once
// What `dpc dashboard` shows, folded from the bench's messages (already read and checked at the
// edge by bus::Read*, so every number here is finite) into one JSON snapshot per push.
//
// The page never sees the bench's rate: a snapshot carries the period's statistics (mean and
// largest error, sample rate, loop-latency percentiles) and at most `max_trail_points` S_in/S_out
// points spread evenly over the period (the sampling stride adapts to the rate), so a 10-kHz
// bench and a 50-Hz one cost the page the same.
//
// Not thread-safe: the command guards it with a mutex. No DDS here, so that it can be tested.

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/bench/bench_messages.h"
#include "dpc/control/target.h"

namespace dpc::tools {

/// 10·log10 of the power a polarizer aligned with the target rejects over what it passes, for
/// an angle `error_deg` on the Poincaré sphere between the SOP and the target: 20·log10(tan(θ/2)).
/// −∞ at 0° is reported as `floor_db` (the page's axis bottom).
double ExtinctionDb(double error_deg, double floor_db = -80.0);

struct DashboardModelOptions {
  double lock_threshold_deg = 10.0;
  size_t max_trail_points = 48;   ///< S_in/S_out points per snapshot
  size_t max_latencies = 4096;    ///< loop latencies kept per period (decimated beyond)
};

class DashboardModel {
 public:
  explicit DashboardModel(DashboardModelOptions options = {});

  void OnSample(const BenchSample& sample);
  void OnState(const DriverState& state);
  void OnDevice(const DeviceDescription& device);
  void OnTarget(const BenchTarget& target);
  void OnStatus(const ControllerStatusReport& status, double now_s);
  /// A message that failed its checks at the edge (never shown, only counted).
  void OnRefused(const std::string& topic, const std::string& problem);

  /// The snapshot at `now_s` (seconds on the caller's monotonic clock) for the period since the
  /// previous call; starts a new period.
  nlohmann::json TakeSnapshot(double now_s);

  /// The condition the latest snapshot reported ("LOCKED", "LOST", "HOLDING", "NO SAMPLES",
  /// "WAITING").
  const std::string& condition() const { return condition_; }

 private:
  void PushTrail(const BenchSample& sample);
  DashboardModelOptions options_;
  std::optional<double> last_snapshot_s_;
  std::string condition_ = "WAITING";
  double condition_since_s_ = 0.0;

  std::optional<BenchTarget> target_;
  std::optional<Target> built_target_;  ///< target_, built once
  std::optional<DeviceDescription> device_;

  // The current period.
  int64_t period_samples_ = 0;
  int64_t period_errors_ = 0;
  double period_error_sum_deg_ = 0.0;
  double period_error_max_deg_ = 0.0;
  std::vector<double> period_latencies_us_;
  int64_t latency_stride_ = 1;
  int64_t latency_counter_ = 0;
  // The trail: every stride-th sample, the stride doubled when the buffer fills.
  std::vector<std::array<double, 6>> trail_;
  int64_t trail_stride_ = 1;
  int64_t trail_counter_ = 0;

  int64_t total_samples_ = 0;
  std::optional<BenchSample> last_sample_;
  std::optional<DriverState> state_;
  uint64_t last_latency_sample_ = 0;
  struct Controller {
    ControllerStatusReport status;
    double received_s = 0.0;
  };
  std::map<std::string, Controller> controllers_;
  std::map<std::string, uint64_t> refused_;  ///< per topic
  std::string last_refusal_;
};

}  // namespace dpc::tools
