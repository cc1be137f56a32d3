#include "dashboard_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "dpc/config/scenario_builders.h"

namespace dpc::tools {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

nlohmann::json Triple(const Vector3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

/// The value at quantile q of `sorted` (nearest rank).
double Quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const auto rank = static_cast<size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::min(sorted.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace

double ExtinctionDb(double error_deg, double floor_db) {
  const double half_rad = std::clamp(error_deg, 0.0, 180.0) / kDegPerRad / 2.0;
  const double t = std::tan(half_rad);
  if (!(t > 0.0)) return floor_db;
  if (!std::isfinite(t)) return 300.0;  // orthogonal: everything rejected
  return std::max(floor_db, 20.0 * std::log10(t));
}

DashboardModel::DashboardModel(DashboardModelOptions options) : options_(options) {
  options_.max_trail_points = std::max<size_t>(2, options_.max_trail_points);
  options_.max_latencies = std::max<size_t>(2, options_.max_latencies);
  trail_.reserve(2 * options_.max_trail_points);
  period_latencies_us_.reserve(options_.max_latencies);
}

void DashboardModel::OnSample(const BenchSample& sample) {
  // A sample numbered at or before the last one is a new bench run (the polarimeter restarted).
  ++period_samples_;
  ++total_samples_;
  last_sample_ = sample;
  PushTrail(sample);
  if (!built_target_) return;
  const double error_deg = built_target_->DistanceRad(sample.s_out) * kDegPerRad;
  if (!std::isfinite(error_deg)) return;
  ++period_errors_;
  period_error_sum_deg_ += error_deg;
  period_error_max_deg_ = period_errors_ == 1 ? error_deg : std::max(period_error_max_deg_, error_deg);
}

void DashboardModel::PushTrail(const BenchSample& sample) {
  if (trail_counter_++ % trail_stride_ != 0) return;
  trail_.push_back({sample.s_in.x(), sample.s_in.y(), sample.s_in.z(), sample.s_out.x(), sample.s_out.y(),
                    sample.s_out.z()});
  if (trail_.size() >= 2 * options_.max_trail_points) {
    // Keep every other point and take every other sample from now on.
    size_t kept = 0;
    for (size_t i = 0; i < trail_.size(); i += 2) trail_[kept++] = trail_[i];
    trail_.resize(kept);
    trail_stride_ *= 2;
  }
}

void DashboardModel::OnState(const DriverState& state) {
  // The loop latency of each newly answered sample: from the sample's publication to the state
  // answering it, both stamped on the bench (the polarimeter's and the driver's wall clocks).
  if (state.answers_sample != 0 && state.answers_sample != last_latency_sample_ &&
      state.sample_publish_time_ns > 0 && state.publish_time_ns >= state.sample_publish_time_ns) {
    last_latency_sample_ = state.answers_sample;
    const double latency_us = static_cast<double>(state.publish_time_ns - state.sample_publish_time_ns) / 1e3;
    if (latency_us < 1e7 && latency_counter_++ % latency_stride_ == 0) {
      period_latencies_us_.push_back(latency_us);
      if (period_latencies_us_.size() >= options_.max_latencies) {
        size_t kept = 0;
        for (size_t i = 0; i < period_latencies_us_.size(); i += 2) period_latencies_us_[kept++] = period_latencies_us_[i];
        period_latencies_us_.resize(kept);
        latency_stride_ *= 2;
      }
    }
  }
  state_ = state;
}

void DashboardModel::OnDevice(const DeviceDescription& device) { device_ = device; }

void DashboardModel::OnTarget(const BenchTarget& target) {
  if (target_ && target.revision < target_->revision) return;  // an older one arriving late
  target_ = target;
  built_target_ = BuildTarget(target.target);
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
  const double period_s = last_snapshot_s_ ? std::max(1e-6, now_s - *last_snapshot_s_) : 0.0;
  last_snapshot_s_ = now_s;

  json snapshot = json::object();
  snapshot["type"] = "snapshot";
  snapshot["t_s"] = now_s;
  snapshot["period_s"] = period_s;

  // The loop's condition, as dpc monitor says it.
  std::optional<double> error_mean_deg;
  if (period_errors_ > 0) error_mean_deg = period_error_sum_deg_ / static_cast<double>(period_errors_);
  std::string condition;
  const bool holding = state_ && state_->mode == DriverMode::kHolding;
  if (total_samples_ == 0 && !state_) {
    condition = "WAITING";
  } else if (period_samples_ == 0) {
    condition = "NO SAMPLES";
  } else if (holding) {
    condition = "HOLDING";
  } else if (error_mean_deg && *error_mean_deg < options_.lock_threshold_deg) {
    condition = "LOCKED";
  } else if (error_mean_deg) {
    condition = "LOST";
  } else {
    condition = "WAITING";  // samples, but no target yet
  }
  if (condition != condition_) {
    condition_ = condition;
    condition_since_s_ = now_s;
  }
  snapshot["condition"] = condition_;
  snapshot["condition_for_s"] = now_s - condition_since_s_;
  snapshot["lock_threshold_deg"] = options_.lock_threshold_deg;

  snapshot["samples"] = {{"total", total_samples_},
                         {"period", period_samples_},
                         {"rate_hz", period_s > 0 ? static_cast<double>(period_samples_) / period_s : 0.0}};
  if (error_mean_deg) {
    snapshot["error_deg"] = {{"mean", *error_mean_deg}, {"max", period_error_max_deg_}};
    snapshot["extinction_db"] = ExtinctionDb(*error_mean_deg);
  } else {
    snapshot["error_deg"] = nullptr;
    snapshot["extinction_db"] = nullptr;
  }
  if (last_sample_) {
    snapshot["s_in"] = Triple(last_sample_->s_in);
    snapshot["s_out"] = Triple(last_sample_->s_out);
    snapshot["sample_sequence"] = last_sample_->sequence;
  } else {
    snapshot["s_in"] = nullptr;
    snapshot["s_out"] = nullptr;
  }
  json trail_in = json::array();
  json trail_out = json::array();
  const size_t step = trail_.size() > options_.max_trail_points ? 2 : 1;
  for (size_t i = 0; i < trail_.size(); i += step) {
    const auto& p = trail_[i];
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
      target["kind"] = "set";
      target["normal"] = Triple(built_target_->normal());
      target["offset"] = built_target_->offset();
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

  if (state_) {
    json saturated = json::array();
    for (int i = 0; i < state_->control_count(); ++i) saturated.push_back(state_->saturated[static_cast<size_t>(i)]);
    snapshot["driver"] = {{"mode", state_->mode == DriverMode::kActive ? "ACTIVE" : "HOLDING"},
                          {"reason", state_->reason},
                          {"obeyed_id", state_->obeyed_controller_id},
                          {"obeyed_priority", state_->obeyed_priority},
                          {"phi", state_->motion.phi},
                          {"saturated", std::move(saturated)},
                          {"commands_applied", state_->commands_applied},
                          {"commands_rejected", state_->commands_rejected},
                          {"commands_limited", state_->commands_limited},
                          {"controller_switches", state_->controller_switches},
                          {"last_rejection", state_->last_rejection}};
  } else {
    snapshot["driver"] = nullptr;
  }

  json controllers = json::array();
  for (const auto& [id, c] : controllers_) {
    const ControllerStatusReport& s = c.status;
    controllers.push_back({{"id", id},
                           {"priority", s.priority},
                           {"law", s.law},
                           {"obeyed", state_ && state_->mode == DriverMode::kActive && state_->obeyed_controller_id == id},
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

  if (!period_latencies_us_.empty()) {
    std::sort(period_latencies_us_.begin(), period_latencies_us_.end());
    snapshot["loop_latency_us"] = {{"p50", Quantile(period_latencies_us_, 0.50)},
                                   {"p90", Quantile(period_latencies_us_, 0.90)},
                                   {"p99", Quantile(period_latencies_us_, 0.99)},
                                   {"max", period_latencies_us_.back()}};
  } else {
    snapshot["loop_latency_us"] = nullptr;
  }
  json refused = json::object();
  for (const auto& [topic, count] : refused_) refused[topic] = count;
  snapshot["refused"] = {{"by_topic", std::move(refused)}, {"last", last_refusal_}};

  // A new period. The trail's stride relaxes when the rate fell.
  const size_t trail_points = trail_.size();
  trail_.clear();
  trail_counter_ = 0;
  if (trail_points < options_.max_trail_points / 2 && trail_stride_ > 1) trail_stride_ /= 2;
  period_samples_ = 0;
  period_errors_ = 0;
  period_error_sum_deg_ = 0.0;
  period_error_max_deg_ = 0.0;
  const size_t latencies = period_latencies_us_.size();
  period_latencies_us_.clear();
  latency_counter_ = 0;
  if (latencies < options_.max_latencies / 2 && latency_stride_ > 1) latency_stride_ /= 2;
  return snapshot;
}

}  // namespace dpc::tools
