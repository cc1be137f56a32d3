#pragma once
// What `dpc dashboard` shows, folded from the bench's low-rate topics (already read and checked
// at the edge by bus::Read*, so every number here is finite) into one JSON snapshot per push.
//
// The bench's rate never reaches the dashboard: the polarimeter's summaries (dpc_bench_summary,
// 20 a second: the period's sample count, mean and largest error, loop-latency percentiles, at
// most 48 S_in/S_out points spread over the period, the driver's latest state) carry it. A
// dashboard subscribed to every sample and state of a 10-kHz bench cost the bench two datagrams
// a sample and the machine ~60 % of a core.
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
#include "dpc/bench/bench_summary.h"

namespace dpc::tools {

/// 10·log10 of the power a polarizer aligned with the target rejects over what it passes, for
/// an angle `error_deg` on the Poincaré sphere between the SOP and the target: 20·log10(tan(θ/2)).
/// −∞ at 0° is reported as `floor_db` (the page's axis bottom).
double ExtinctionDb(double error_deg, double floor_db = -80.0);

struct DashboardModelOptions {
  double lock_threshold_deg = 10.0;
  double stale_s = 1.0;  ///< no summary for this long: NO SAMPLES (the bench stopped)
};

class DashboardModel {
 public:
  explicit DashboardModel(DashboardModelOptions options = {});

  /// A summary of the bench received at `now_s` (seconds on the caller's monotonic clock).
  void OnSummary(const BenchSummary& summary, double now_s);
  void OnDevice(const DeviceDescription& device);
  void OnTarget(const BenchTarget& target);
  void OnStatus(const ControllerStatusReport& status, double now_s);
  /// A message that failed its checks at the edge (never shown, only counted).
  void OnRefused(const std::string& topic, const std::string& problem);

  /// The snapshot at `now_s` for the period since the previous call (`fresh`: summaries arrived
  /// in it; the page plots only fresh ones); starts a new period.
  nlohmann::json TakeSnapshot(double now_s);

  /// The condition the latest snapshot reported ("LOCKED", "LOST", "HOLDING", "NO SAMPLES",
  /// "WAITING").
  const std::string& condition() const { return condition_; }

 private:
  DashboardModelOptions options_;
  std::string condition_ = "WAITING";
  double condition_since_s_ = 0.0;

  std::optional<BenchTarget> target_;
  std::optional<DeviceDescription> device_;

  // The summaries of the current period, folded.
  int summaries_ = 0;
  uint64_t period_samples_ = 0;
  double period_bench_s_ = 0.0;       ///< the summaries' own periods, summed
  uint64_t period_errors_ = 0;        ///< samples behind the error figures
  double period_error_sum_deg_ = 0.0; ///< mean × samples, summed
  double period_error_max_deg_ = 0.0;
  std::vector<std::array<double, 6>> trail_;
  // The latest summary (kept across periods).
  std::optional<BenchSummary> latest_;
  double latest_received_s_ = 0.0;
  std::optional<double> rate_hz_;
  std::optional<double> error_mean_deg_;
  double error_max_deg_ = 0.0;

  struct Controller {
    ControllerStatusReport status;
    double received_s = 0.0;
  };
  std::map<std::string, Controller> controllers_;
  std::map<std::string, uint64_t> refused_;  ///< per topic
  std::string last_refusal_;
};

}  // namespace dpc::tools
