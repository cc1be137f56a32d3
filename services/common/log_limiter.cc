#include "log_limiter.h"

#include <algorithm>

#include <fmt/format.h>

#include "dpc/bench/clock.h"

namespace dpc::services {

LogLimiter::LogLimiter(std::chrono::nanoseconds interval, Now now)
    : interval_ns_(interval.count()), now_(now ? std::move(now) : Now(MonotonicNs)) {}

bool LogLimiter::Log(spdlog::level::level_enum level, const std::string& key, const std::string& message) {
  const int64_t now_ns = now_();
  auto found = entries_.find(key);
  if (found != entries_.end() && now_ns - found->second.logged_ns < interval_ns_) {
    ++found->second.suppressed;
    return false;
  }
  if (found == entries_.end()) {
    if (entries_.size() >= kMaxKeys) {
      entries_.erase(std::min_element(entries_.begin(), entries_.end(), [](const auto& a, const auto& b) {
        return a.second.logged_ns < b.second.logged_ns;
      }));
    }
    found = entries_.emplace(key, Entry{}).first;
    spdlog::log(level, "{}", message);
  } else if (found->second.suppressed > 0) {
    spdlog::log(level, "{} ({} more like this in the last {:.1f} s)", message, found->second.suppressed,
                static_cast<double>(now_ns - found->second.logged_ns) * 1e-9);
  } else {
    spdlog::log(level, "{}", message);
  }
  found->second.logged_ns = now_ns;
  found->second.suppressed = 0;
  return true;
}

std::string LogLimiter::KeyOf(std::string_view message) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  std::string key;
  key.reserve(message.size());
  for (size_t i = 0; i < message.size();) {
    if (!digit(message[i])) {
      key += message[i++];
      continue;
    }
    key += '#';
    while (i < message.size() &&
           (digit(message[i]) ||
            ((message[i] == '.' || message[i] == ',') && i + 1 < message.size() && digit(message[i + 1])))) {
      ++i;
    }
  }
  return key;
}

std::string LogLimiter::KindOf(std::string_view message) {
  return std::string(message.substr(0, message.find_first_of(":(0123456789")));
}

uint64_t LogLimiter::suppressed(const std::string& key) const {
  const auto found = entries_.find(key);
  return found == entries_.end() ? 0 : found->second.suppressed;
}

}  // namespace dpc::services
