#pragma once
// The shared harness of dpc_bus_benchmark: what every section needs (the domain, this binary,
// the log directory, --quick), the percentile summaries it prints, and the launchers of the
// bench's real services and of this binary's own internal modes. No globals: main() builds one
// harness and passes it to each section.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "support/process.h"

namespace dpc::bus_benchmark {

using testing::Process;

/// Percentiles of a series, in the series' unit (ns for every span in this binary); NAN when the
/// series is empty.
struct Percentiles {
  double p50 = NAN, p99 = NAN, p999 = NAN, max = NAN;
  size_t count = 0;
};

/// Nearest-rank percentiles of `values`.
Percentiles Summarize(std::vector<double> values);

/// "p50 … µs  p99 … µs  p99.9 … µs  (n = …)" of percentiles in ns.
std::string Us(const Percentiles& p);

/// One run of the benchmark, passed to every section.
struct BusBenchmarkHarness {
  int domain = 30;      ///< the bench's DDS domain (loopback profile); the raw references use RawDomain()
  std::string self;     ///< this binary, re-executed for the far sides of the raw references
  std::string log_dir;  ///< one log per child process (its stdout and stderr)
  bool quick = false;   ///< short runs (~3 min in all) instead of the full ones (~20 min)

  /// The harness of this run: logs in a fresh <tmp>/dpc_bus_benchmark_<pid>.
  static BusBenchmarkHarness Create(int domain, bool quick);

  /// The raw references' own domains (1: ping-pong, 2: chain): an echo must not answer the
  /// bench's samples or another reference's.
  int RawDomain(int which = 1) const;

  /// <log_dir>/<name>.log
  std::string LogPath(const std::string& name) const;

  /// This binary in one of its internal modes (`args`, e.g. {"--pong", "--domain", "31"}),
  /// logging to LogPath(log_name); ended (SIGINT, then SIGKILL) when the pointer goes.
  std::unique_ptr<Process> StartSelf(std::vector<std::string> args, const std::string& log_name) const;
};

/// The bench's real services (dpc-driver, dpc-controller, dpc-polarimeter) on the harness's
/// domain, each logging to <log_dir>/<service><log_suffix>.log; all stopped when this goes.
class Services {
 public:
  explicit Services(const BusBenchmarkHarness& harness, std::string log_suffix = "")
      : harness_(harness), log_suffix_(std::move(log_suffix)) {}
  Process& Start(const std::string& binary, std::vector<std::string> args, const std::string& name);
  Process& Driver();
  Process& Controller(const std::string& id, int priority, std::vector<std::string> extra = {});
  Process& Polarimeter(std::vector<std::string> args);
  void StopAll() { processes_.clear(); }
  /// Arguments every service started from now on gets (e.g. --security-dir DIR).
  void AddCommonArgs(std::vector<std::string> args) { common_args_ = std::move(args); }

 private:
  const BusBenchmarkHarness& harness_;
  std::string log_suffix_;
  std::vector<std::string> common_args_;
  std::vector<std::unique_ptr<Process>> processes_;
};

/// One real-time run of the bench (driver, one controller "main", polarimeter at `rate_hz`):
/// what the polarimeter reported and the CPU time of the three services per sample.
struct RealTimeRun {
  bool ok = false;
  double achieved_hz = NAN, loop_p50_us = NAN, loop_p99_us = NAN, cpu_us_per_sample = NAN, error_mean_deg = NAN;
  int64_t overruns = 0, state_deadline_misses = 0;
};

/// Starts the bench with `common_args` (e.g. --security-dir DIR) and the profiles file the
/// environment names, waits 1 s for discovery (and handshakes), starts the polarimeter at
/// `rate_hz`, warms up for 2 s, measures for `seconds`; logs get `label`.
RealTimeRun RunRealTimeBench(const BusBenchmarkHarness& harness, double rate_hz, double seconds,
                             const std::string& label, std::vector<std::string> common_args = {});

/// "achieved … Hz (… overruns), loop p50 … µs p99 … µs, CPU … µs/sample, error mean …°".
std::string Row(const RealTimeRun& run);

/// "loop p50 +…%, p99 +…%, CPU per sample +…%, rate +…%": `run` against `base` (both ok).
std::string Change(const RealTimeRun& base, const RealTimeRun& run);

}  // namespace dpc::bus_benchmark
