#pragma once
// A one-line progress display on stderr for long runs:
//   [██████████░░░░░░░░░░]  52%  26.0 M of 50.0 M samples  18.3 M/s  ETA 1.3 s
// Redrawn at most every 100 ms; cleared on Finish(). Only active when enabled (by default when
// stderr is a terminal).

#include <chrono>
#include <cstdint>
#include <string>

namespace dpc::tools {

class ProgressBar {
 public:
  ProgressBar(std::string label, bool enabled);
  ~ProgressBar();

  /// Redraws if at least 100 ms passed since the last draw.
  void Update(int64_t done, int64_t total);
  /// Clears the line.
  void Finish();

  static bool StderrIsTerminal();

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace dpc::tools
