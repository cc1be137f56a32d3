#include "dashboard_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "dpc/config/scenario_builders.h"

namespace dpc::tools {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

nlohmann::json Triple(const Vector3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace

double ExtinctionDb(double error_deg, double floor_db) {
  const double half_rad = std::clamp(error_deg, 0.0, 180.0) / kDegPerRad / 2.0;
  const double t = std::tan(half_rad);
  if (!(t > 0.0)) return floor_db;
  if (!std::isfinite(t)) return 300.0;  // orthogonal: everything rejected
  return std::max(floor_db, 20.0 * std::log10(t));
}

DashboardModel::DashboardModel(DashboardModelOptions options) : options_(options) {}

void DashboardModel::OnSummary(const BenchSummary& summary, double now_s) {
  if (latest_ && summary.sequence <= latest_->sequence && summary.publish_time_ns <= latest_->publish_time_ns) {
    return;  // an old one arriving late (a restarted polarimeter numbers from 1 again, later)
  }
  ++summaries_;
  period_samples_ += summary.samples;
  period_bench_s_ += summary.period_s;
  if (summary.error_mean_deg) {
    period_error_sum_deg_ += *summary.error_mean_deg * static_cast<double>(summary.samples);
    period_errors_ += summary.samples;
    period_error_max_deg_ =
        period_errors_ == summary.samples ? summary.error_max_deg : std::max(period_error_max_deg_, summary.error_max_deg);
  }
  for (const auto& point : summary.trail) {
    if (trail_.size() >= 4 * kMaxSummaryTrailPoints) break;  // pushes far slower than summaries
    trail_.push_back(point);
  }
  latest_ = summary;
  latest_received_s_ = now_s;
}

void DashboardModel::OnDevice(const DeviceDescription& device) { device_ = device; }

void DashboardModel::OnTarget(const BenchTarget& target) {
  if (target_ && target.revision < target_->revision) return;  // an older one arriving late
  target_ = target;
}

void DashboardModel::OnStatus(const ControllerStatusReport& status, double now_s) {
  if (controllers_.size() >= 64 && controllers_.count(status.controller_id) == 0) {
    // A bench has at most 64 controllers; forget the one silent for longest.
    auto oldest = std::min_element(controllers_.begin(), controllers_.end(), [](const auto& a, const auto& b) {
      return a.second.received_s < b.second.received_s;
    });
    controllers_.erase(oldest);
  }
  Controller& c = controllers_[status.controller_id];
  c.status = status;
  c.received_s = now_s;
}

void DashboardModel::OnRefused(const std::string& topic, const std::string& problem) {
  ++refused_[topic];
  last_refusal_ = topic + ": " + problem;
}

nlohmann::json DashboardModel::TakeSnapshot(double now_s) {
  using nlohmann::json;
  json snapshot = json::object();
  snapshot["type"] = "snapshot";
  snapshot["t_s"] = now_s;
  const bool fresh = summaries_ > 0;
  snapshot["fresh"] = fresh;
  if (fresh) {
    rate_hz_ = period_bench_s_ > 0 ? std::optional<double>(static_cast<double>(period_samples_) / period_bench_s_)
                                   : std::nullopt;
    error_mean_deg_.reset();
    if (period_errors_ > 0) {
      error_mean_deg_ = period_error_sum_deg_ / static_cast<double>(period_errors_);
      error_max_deg_ = period_error_max_deg_;
    }
  }
  const bool stale = !latest_ || now_s - latest_received_s_ > options_.stale_s;

  // The loop's condition, as dpc monitor says it.
  std::string condition;
  const bool holding = latest_ && latest_->state && latest_->state->mode == DriverMode::kHolding;
  if (!latest_) {
    condition = "WAITING";
  } else if (stale || (fresh && period_samples_ == 0)) {
    condition = "NO SAMPLES";
  } else if (holding) {
    condition = "HOLDING";
  } else if (error_mean_deg_ && *error_mean_deg_ < options_.lock_threshold_deg) {
    condition = "LOCKED";
  } else if (error_mean_deg_) {
    condition = "LOST";
  } else {
    condition = condition_ == "NO SAMPLES" ? "WAITING" : condition_;
  }
  if (condition != condition_) {
    condition_ = condition;
    condition_since_s_ = now_s;
  }
  snapshot["condition"] = condition_;
  snapshot["condition_for_s"] = now_s - condition_since_s_;
  snapshot["lock_threshold_deg"] = options_.lock_threshold_deg;
  snapshot["summary_age_s"] = latest_ ? json(now_s - latest_received_s_) : json(nullptr);

  snapshot["samples"] = {{"last", latest_ ? latest_->last_sample : 0},
                         {"period", period_samples_},
                         {"rate_hz", !stale && rate_hz_ ? *rate_hz_ : 0.0}};
  if (error_mean_deg_ && !stale) {
    snapshot["error_deg"] = {{"mean", *error_mean_deg_}, {"max", error_max_deg_}};
    snapshot["extinction_db"] = ExtinctionDb(*error_mean_deg_);
  } else {
    snapshot["error_deg"] = nullptr;
    snapshot["extinction_db"] = nullptr;
  }
  if (latest_ && latest_->last_sample != 0) {
    snapshot["s_in"] = Triple(latest_->s_in);
    snapshot["s_out"] = Triple(latest_->s_out);
  } else {
    snapshot["s_in"] = nullptr;
    snapshot["s_out"] = nullptr;
  }
  json trail_in = json::array();
  json trail_out = json::array();
  for (const auto& p : trail_) {
    trail_in.push_back({p[0], p[1], p[2]});
    trail_out.push_back({p[3], p[4], p[5]});
  }
  snapshot["trail"] = {{"s_in", std::move(trail_in)}, {"s_out", std::move(trail_out)}};

  if (target_) {
    const TargetConfig& t = target_->target;
    // The revision as text: epoch << 32 | count exceeds the 2^53 a JavaScript number holds.
    json target = {{"revision", std::to_string(target_->revision)},
                   {"revision_epoch", RevisionEpoch(target_->revision)},
                   {"revision_count", RevisionCount(target_->revision)},
                   {"request_id", target_->request_id}};
    if (t.kind == TargetConfig::Kind::kPoint) {
      target["kind"] = "point";
      target["point"] = Triple(t.point);
    } else {
      const Target set = BuildTarget(t);  // normalized: n·S = c with |n| = 1
      target["kind"] = "set";
      target["normal"] = Triple(set.normal());
      target["offset"] = set.offset();
    }
    snapshot["target"] = std::move(target);
  } else {
    snapshot["target"] = nullptr;
  }

  if (device_) {
    json stages = json::array();
    for (const StageConfig& stage : device_->stages) {
      json s = {{"name", stage.name}};
      if (stage.range) {
        s["min"] = stage.range->min;
        s["max"] = stage.range->max;
      } else {
        s["min"] = nullptr;
        s["max"] = nullptr;
      }
      stages.push_back(std::move(s));
    }
    snapshot["device"] = {{"driver_id", device_->driver_id},
                          {"stages", std::move(stages)},
                          {"max_slew_per_s", device_->max_slew_per_s},
                          {"max_ramp_s", device_->max_ramp_s}};
  } else {
    snapshot["device"] = nullptr;
  }

  const DriverState* state = latest_ && latest_->state ? &*latest_->state : nullptr;
  if (state != nullptr) {
    json saturated = json::array();
    json phi = json::array();
    for (int i = 0; i < state->control_count(); ++i) {
      saturated.push_back(state->saturated[static_cast<size_t>(i)]);
      phi.push_back(state->motion.phi[i]);
    }
    snapshot["driver"] = {{"mode", state->mode == DriverMode::kActive ? "ACTIVE" : "HOLDING"},
                          {"reason", state->reason},
                          {"obeyed_id", state->obeyed_controller_id},
                          {"obeyed_priority", state->obeyed_priority},
                          {"phi", std::move(phi)},
                          {"saturated", std::move(saturated)},
                          {"commands_applied", state->commands_applied},
                          {"commands_rejected", state->commands_rejected},
                          {"commands_limited", state->commands_limited},
                          {"controller_switches", state->controller_switches}};
  } else {
    snapshot["driver"] = nullptr;
  }

  json controllers = json::array();
  for (const auto& [id, c] : controllers_) {
    const ControllerStatusReport& s = c.status;
    controllers.push_back({{"id", id},
                           {"priority", s.priority},
                           {"law", s.law},
                           {"obeyed", state != nullptr && state->mode == DriverMode::kActive && state->obeyed_controller_id == id},
                           {"condition", s.condition},
                           {"error_deg", s.error_deg},
                           {"sigma_min", s.sigma_min},
                           {"sigma_max", s.sigma_max},
                           {"compute_mean_us", s.compute_time_mean_s * 1e6},
                           {"compute_max_us", s.compute_time_max_s * 1e6},
                           {"missed_deadlines", s.missed_deadlines},
                           {"updates", s.updates},
                           {"silent_s", now_s - c.received_s}});
  }
  snapshot["controllers"] = std::move(controllers);

  if (latest_ && latest_->latencies > 0 && !stale) {
    snapshot["loop_latency_us"] = {{"p50", latest_->latency_p50_us},
                                   {"p90", latest_->latency_p90_us},
                                   {"p99", latest_->latency_p99_us},
                                   {"max", latest_->latency_max_us},
                                   {"count", latest_->latencies}};
  } else {
    snapshot["loop_latency_us"] = nullptr;
  }
  json refused = json::object();
  for (const auto& [topic, count] : refused_) refused[topic] = count;
  snapshot["refused"] = {{"by_topic", std::move(refused)}, {"last", last_refusal_}};

  // A new period.
  summaries_ = 0;
  period_samples_ = 0;
  period_bench_s_ = 0.0;
  period_errors_ = 0;
  period_error_sum_deg_ = 0.0;
  period_error_max_deg_ = 0.0;
  trail_.clear();
  return snapshot;
}

}  // namespace dpc::tools
