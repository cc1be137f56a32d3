#pragma once
// A one-line progress display on stderr for long runs:
//   [██████████░░░░░░░░░░]  52%  26.0 M of 50.0 M samples  18.3 M/s  ETA 1.3 s
// Redrawn at most every 100 ms; cleared on Finish(). Only active when enabled (by default when
// stderr is a terminal).

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace dpc::tools {

class ProgressBar {
 public:
  using Clock = std::chrono::steady_clock;
  /// The time source (tests pass their own); default: the steady clock.
  using Now = std::function<Clock::time_point()>;

  ProgressBar(std::string label, bool enabled, Now now = Clock::now);
  ~ProgressBar();

  /// Redraws if at least 100 ms passed since the last draw.
  void Update(int64_t done, int64_t total);
  /// Clears the line.
  void Finish();

  static bool StderrIsTerminal();

 private:
  std::string label_;
  bool enabled_;
  Now now_;
  bool drawn_ = false;
  Clock::time_point start_;
  Clock::time_point last_draw_;
};

}  // namespace dpc::tools
