#pragma once
// Keeps repeated log lines from flooding a service's log: a line is written the first time its
// key appears, then at most once per interval for that key, saying how many lines it stands for
// ("… (37 more like this in the last 5.0 s)"). A stopped polarimeter makes a controller's
// condition change 50 times a second; a peer may send refused requests as fast as it likes.
//
// Bounded: at most kMaxKeys keys are remembered (the one logged longest ago is forgotten).

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>

#include <spdlog/spdlog.h>

namespace dpc::services {

class LogLimiter {
 public:
  static constexpr size_t kMaxKeys = 64;
  using Now = std::function<int64_t()>;  ///< monotonic nanoseconds

  /// `now` defaults to the monotonic clock.
  explicit LogLimiter(std::chrono::nanoseconds interval = std::chrono::seconds(5), Now now = nullptr);

  /// Logs `message` at `level` unless a line of `key` was logged less than the interval ago (then
  /// it is counted). Returns whether it logged.
  bool Log(spdlog::level::level_enum level, const std::string& key, const std::string& message);

  /// A key for a message whose figures change from line to line: the message with each number
  /// (a run of digits, with the points and commas between them) replaced by '#'. "holding: main
  /// silent for 3.25 ms" and "… for 41.70 ms" share a key; "holding: no controller yet" does not.
  static std::string KeyOf(std::string_view message);
  /// A coarser key, for a condition whose text after its kind names a cause that may vary (a
  /// controller's "unusable device description: …"): the message up to its first ':', '(' or
  /// digit. "frozen" for "frozen: no sample for 25 ms", "standby " for "standby (following …)".
  static std::string KindOf(std::string_view message);

  /// Lines of `key` counted but not logged since its last line.
  uint64_t suppressed(const std::string& key) const;

 private:
  struct Entry {
    int64_t logged_ns = 0;
    uint64_t suppressed = 0;
  };
  int64_t interval_ns_;
  Now now_;
  std::map<std::string, Entry> entries_;
};

}  // namespace dpc::services
