#include "instrument_polarimeter.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "dpc/bench/clock.h"

namespace dpc::services {

InstrumentPolarimeter::InstrumentPolarimeter(PolarimeterDeviceConfig device)
    : device_(std::move(device)), link_(device_.link), backoff_s_(device_.link.reconnect_min_s) {}

std::string InstrumentPolarimeter::name() const { return "polarimeter (" + link_.Describe() + ")"; }

std::optional<PolarimeterReading> InstrumentPolarimeter::Measure(int64_t now_ns, std::string* why) {
  const double timeout_s = device_.link.response_timeout_s;
  if (!link_.is_open()) {
    if (now_ns < next_connect_ns_) {
      *why = fmt::format("not connected (next attempt in {:.2f} s)", static_cast<double>(next_connect_ns_ - now_ns) * 1e-9);
      return std::nullopt;
    }
    if (std::string failure = link_.Open(timeout_s * 4 + 0.1); !failure.empty()) {
      ++counters_.failed_connects;
      next_connect_ns_ = now_ns + static_cast<int64_t>(backoff_s_ * 1e9);
      backoff_s_ = std::min(backoff_s_ * 2, device_.link.reconnect_max_s);
      *why = "cannot connect: " + failure;
      return std::nullopt;
    }
    ++counters_.connects;
    backoff_s_ = device_.link.reconnect_min_s;
    if (device_.stream && !device_.stream_start.empty()) {
      if (std::string failure = link_.WriteLine(device_.stream_start, timeout_s); !failure.empty()) {
        next_connect_ns_ = MonotonicNs() + static_cast<int64_t>(backoff_s_ * 1e9);
        *why = fmt::format("starting the stream ({}): {}", device_.stream_start, failure);
        return std::nullopt;
      }
    }
  }
  std::string failure;
  std::optional<std::string> reply;
  int64_t reply_ns = 0;
  if (device_.stream) {
    reply = link_.ReadNewestLine(timeout_s, &failure, &counters_.overtaken);
    reply_ns = MonotonicNs();
  } else {
    ++counters_.queries;
    const int64_t query_ns = MonotonicNs();
    reply = link_.Query(device_.query, timeout_s, &failure);
    reply_ns = MonotonicNs();
    if (reply) query_times_.Add(static_cast<double>(reply_ns - query_ns) * 1e-3);
  }
  static const std::string kStream = "the stream";
  const std::string& asked = device_.stream ? kStream : device_.query;  // named in every failure
  if (!reply) {
    if (!link_.is_open()) {
      next_connect_ns_ = reply_ns + static_cast<int64_t>(backoff_s_ * 1e9);
    } else {
      ++counters_.timeouts;
    }
    *why = fmt::format("{}: {}", asked, failure);
    return std::nullopt;
  }
  using Reply = PolarimeterDeviceConfig::Reply;
  StokesVector values[2];
  const int vectors = device_.reply == Reply::kInputAndOutput ? 2 : 1;
  std::string stokes = *reply;
  std::optional<double> power_w;
  if (device_.reports_power) {
    // The last field is the optical power.
    const size_t comma = stokes.rfind(',');
    double power = 0.0;
    std::string bad = comma == std::string::npos ? "no power field"
                                                 : instrument::ParseNumberReply(stokes.substr(comma + 1), &power);
    if (bad.empty() && !(power >= 0.0)) bad = fmt::format("a power of {} W", power);
    if (!bad.empty()) {
      ++counters_.refused_replies;
      *why = fmt::format("{}: the power: {}", asked, bad);
      return std::nullopt;
    }
    power_w = power;
    stokes.resize(comma);
  }
  if (std::string bad = instrument::ParseStokesReply(stokes, vectors, device_.min_dop, values); !bad.empty()) {
    ++counters_.refused_replies;
    *why = fmt::format("{}: {}", asked, bad);
    return std::nullopt;
  }
  PolarimeterReading reading;
  reading.reply_ns = reply_ns;
  reading.power_w = power_w;
  switch (device_.reply) {
    case Reply::kOutput: reading.s_out = values[0]; break;
    case Reply::kInput: reading.s_in = values[0]; break;
    case Reply::kInputAndOutput:
      reading.s_in = values[0];
      reading.s_out = values[1];
      break;
  }
  ++counters_.readings;
  return reading;
}

}  // namespace dpc::services
