#include "line_waveplates.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "dpc/config/scenario_validation.h"

namespace dpc::services {
namespace {

using Clock = std::chrono::steady_clock;

/// While idle, the device is checked this often: read back (it may have lost power and its
/// voltages while the link stayed open, as a serial port does) or identified.
constexpr double kKeepaliveS = 0.5;

std::string Trim(std::string text) {
  const size_t first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  const size_t last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

/// A reply for a log line: bounded, control characters shown as '?'.
std::string Shown(const std::string& reply) {
  std::string shown = reply.substr(0, 60);
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return shown + (reply.size() > 60 ? "…" : "");
}

}  // namespace

LineWaveplates::LineWaveplates(WaveplateDeviceConfig device, const ControlVector& initial_phi,
                               const std::vector<ControlRange>& ranges, Log log, double connect_timeout_s)
    : device_(std::move(device)),
      name_(fmt::format("line device ({})", instrument::LineLink(device_.link).Describe())),
      log_(std::move(log)),
      link_(device_.link) {
  for (Eigen::Index i = 0; i < initial_phi.size(); ++i) {
    channels_.push_back(device_.channels.empty() ? static_cast<int>(i) + 1 : device_.channels[static_cast<size_t>(i)]);
    wanted_.push_back(Dac(initial_phi[i]));
  }
  std::string failure = Connect(connect_timeout_s);
  if (failure.empty() && !device_.read_command.empty()) {
    std::vector<double> volts;
    failure = ReadBack(&volts);
    if (failure.empty()) {
      // The waveplates stay where they are: a restarted driver does not move them.
      for (size_t i = 0; i < volts.size(); ++i) {
        const double v = i < ranges.size() ? ranges[i].Clamp(volts[i]) : volts[i];
        wanted_[i] = Dac(v);
      }
      started_from_read_back_ = true;
    }
  }
  if (failure.empty()) failure = Send(wanted_, true);
  ControlVector phi(static_cast<Eigen::Index>(wanted_.size()));
  for (size_t i = 0; i < wanted_.size(); ++i) phi[static_cast<Eigen::Index>(i)] = wanted_[i].volts;
  applied_ = WaveplateMotion::Still(phi);
  if (!failure.empty()) {
    link_.Close();
    SetFault(failure);
  } else if (log_) {
    log_(false, fmt::format("{}: connected; {} at [{}] V", name_,
                            started_from_read_back_ ? "read back" : "set",
                            fmt::join(std::vector<double>(phi.data(), phi.data() + phi.size()), ", ")));
  }
  thread_ = std::thread([this] { Run(); });
}

LineWaveplates::~LineWaveplates() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

DeviceLimits LineWaveplates::limits() const {
  return DeviceLimits{std::max(std::abs(device_.volts_min), std::abs(device_.volts_max)), device_.max_slew_v_per_s};
}

instrument::DacPoint LineWaveplates::Dac(double volts) const {
  return instrument::Quantize(volts, device_.volts_min, device_.volts_max, device_.dac_bits);
}

std::string LineWaveplates::Apply(const WaveplateMotion& motion) {
  std::vector<instrument::DacPoint> target;
  target.reserve(channels_.size());
  for (Eigen::Index i = 0; i < motion.phi.size(); ++i) {
    const double volts = motion.phi[i];
    // The driver clamps into the ranges, which validation keeps inside the full scale: this is
    // the last guard before the wire.
    if (!(volts >= device_.volts_min && volts <= device_.volts_max)) {
      return fmt::format("φ_{} = {} V is outside the device's full scale [{}, {}] V", i + 1, volts, device_.volts_min,
                         device_.volts_max);
    }
    target.push_back(Dac(volts));
  }
  if (target.size() != channels_.size()) {
    return fmt::format("{} values for {} channels", target.size(), channels_.size());
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!fault_.empty()) return fault_;
    wanted_ = target;
    ++wanted_version_;
  }
  wake_.notify_one();
  for (size_t i = 0; i < target.size(); ++i) applied_.phi[static_cast<Eigen::Index>(i)] = target[i].volts;
  applied_.rate_per_s.setZero();
  applied_.start_ns = motion.start_ns;
  applied_.end_ns = motion.start_ns;
  applied_.moving = false;
  return {};
}

std::string LineWaveplates::fault() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fault_;
}

LineWaveplates::Counters LineWaveplates::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

void LineWaveplates::CountMissingReply() {
  // A reply that did not come on a link still open is a timeout; a closed link is a disconnect.
  if (!link_.is_open()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.timeouts;
}

std::pair<double, double> LineWaveplates::ApplyTimesUs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {apply_times_.Percentile(0.5), apply_times_.Percentile(0.99)};
}

void LineWaveplates::SetFault(std::string why) {
  bool changed = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    changed = fault_ != why;
    fault_ = std::move(why);
  }
  if (changed && log_) log_(true, fmt::format("{}: {}", name_, fault()));
}

std::string LineWaveplates::Connect(double timeout_s) {
  if (std::string failure = link_.Open(timeout_s); !failure.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.failed_connects;
    return "cannot connect: " + failure;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.connects;
  }
  device_codes_.clear();  // what a device that was away holds is unknown
  if (device_.identify.empty()) return {};
  std::string why;
  const auto reply = link_.Query(device_.identify, device_.link.response_timeout_s, &why);
  if (!reply) {
    CountMissingReply();
    return fmt::format("{}: {}", device_.identify, why);
  }
  if (log_) log_(false, fmt::format("{}: {} → {}", name_, device_.identify, Shown(*reply)));
  return {};
}

std::string LineWaveplates::ReadBack(std::vector<double>* volts) {
  volts->clear();
  for (const int channel : channels_) {
    std::string why;
    const std::string query = FormatSetCommand(device_.read_command, channel, 0.0, 0);
    const auto reply = link_.Query(query, device_.link.response_timeout_s, &why);
    double value = 0.0;
    if (!reply) {
      CountMissingReply();
      return fmt::format("{}: {}", query, why);
    }
    if (std::string bad = instrument::ParseNumberReply(*reply, &value); !bad.empty()) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++counters_.refused_replies;
      return fmt::format("{}: {}", query, bad);
    }
    volts->push_back(value);
  }
  return {};
}

std::string LineWaveplates::Send(const std::vector<instrument::DacPoint>& target, bool all) {
  std::vector<size_t> sent;
  link_.Discard();
  for (size_t i = 0; i < target.size(); ++i) {
    if (!all && i < device_codes_.size() && device_codes_[i].code == target[i].code &&
        device_codes_[i].volts == target[i].volts) {
      continue;
    }
    const std::string line = FormatSetCommand(device_.set_command, channels_[i], target[i].volts, target[i].code);
    if (std::string failure = link_.WriteLine(line, device_.link.response_timeout_s); !failure.empty()) {
      return fmt::format("{}: {}", line, failure);
    }
    sent.push_back(i);
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    counters_.sets += sent.size();
  }
  if (device_codes_.size() != target.size()) device_codes_.assign(target.size(), instrument::DacPoint{-1, NAN});
  for (const size_t i : sent) {
    if (!device_.ack.empty()) {
      std::string why;
      const auto reply = link_.ReadLine(device_.link.response_timeout_s, &why);
      if (!reply) {
        CountMissingReply();
        return fmt::format("setting channel {}: {}", channels_[i], why);
      }
      if (Trim(*reply) != device_.ack) {
        std::lock_guard<std::mutex> lock(mutex_);
        ++counters_.refused_replies;
        return fmt::format("setting channel {}: the device answered \"{}\", not \"{}\"", channels_[i], Shown(*reply),
                           device_.ack);
      }
    }
    device_codes_[i] = target[i];
  }
  return {};
}

void LineWaveplates::Run() {
  const double min_s = device_.link.reconnect_min_s, max_s = device_.link.reconnect_max_s;
  double backoff_s = min_s;
  uint64_t sent_version = 0;
  auto next_keepalive = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kKeepaliveS));
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    if (!link_.is_open()) {
      // Reconnect after the backoff, then set the device to the held φ before anyone drives it.
      if (wake_.wait_for(lock, std::chrono::duration<double>(backoff_s), [&] { return stop_; })) break;
      const std::vector<instrument::DacPoint> held = wanted_;
      const uint64_t version = wanted_version_;
      lock.unlock();
      std::string failure = Connect(device_.link.response_timeout_s * 4 + 0.1);
      if (failure.empty()) failure = Send(held, true);
      if (!failure.empty()) {
        link_.Close();
        SetFault(failure + fmt::format(" (next attempt in {:g} s)", std::min(backoff_s * 2, max_s)));
        backoff_s = std::min(backoff_s * 2, max_s);
        lock.lock();
        continue;
      }
      backoff_s = min_s;
      lock.lock();
      sent_version = version;
      fault_.clear();
      lock.unlock();
      if (log_) log_(false, fmt::format("{}: reconnected; set to the held φ", name_));
      lock.lock();
      continue;
    }
    wake_.wait_until(lock, next_keepalive, [&] { return stop_ || wanted_version_ != sent_version; });
    if (stop_) break;
    const bool idle = wanted_version_ == sent_version;
    const std::vector<instrument::DacPoint> target = wanted_;
    const uint64_t version = wanted_version_;
    lock.unlock();
    std::string failure;
    if (!idle) {
      const auto sent_at = Clock::now();
      failure = Send(target, false);
      if (failure.empty()) {
        const double us = std::chrono::duration<double, std::micro>(Clock::now() - sent_at).count();
        lock.lock();
        apply_times_.Add(us);
        // Not set again before the output settled: newer commands meanwhile are coalesced.
        if (device_.settling_s > 0) {
          wake_.wait_for(lock, std::chrono::duration<double>(device_.settling_s), [&] { return stop_; });
        }
        lock.unlock();
      }
    } else {
      // Idle: is the device still there, and does it still hold what it was set to?
      if (!device_.read_command.empty()) {
        std::vector<double> volts;
        failure = ReadBack(&volts);
        const double lsb = device_.dac_bits > 0 ? (device_.volts_max - device_.volts_min) / (std::ldexp(1.0, device_.dac_bits) - 1.0) : 1e-6;
        for (size_t i = 0; failure.empty() && i < volts.size() && i < device_codes_.size(); ++i) {
          if (std::abs(volts[i] - device_codes_[i].volts) > lsb + 1e-6) {
            failure = fmt::format("channel {} reads {} V, not the {} V it was set to (did the device lose power?)",
                                  channels_[i], volts[i], device_codes_[i].volts);
          }
        }
      } else if (!device_.identify.empty()) {
        std::string why;
        if (!link_.Query(device_.identify, device_.link.response_timeout_s, &why)) {
          CountMissingReply();
          failure = device_.identify + ": " + why;
        }
      }
      next_keepalive = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kKeepaliveS));
    }
    if (!failure.empty()) {
      link_.Close();
      SetFault(failure);
      backoff_s = min_s;
    }
    lock.lock();
    if (failure.empty() && !idle) sent_version = version;
  }
}

}  // namespace dpc::services
