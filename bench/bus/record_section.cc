// The record section of dpc_bus_benchmark: `dpc record` of a running real-time bench at 2 and
// 10 kHz requested (goal at 10 kHz: every sample kept, counted against the polarimeter's
// sequence numbers, at ≤ 10 % of one core). For each rate: the recorder of every topic, the
// recorder of the samples alone, and the DDS floor beside them (`dpc topic hz sample`, a typed
// reader of the samples that keeps nothing): CPU over a steady window (% of one core), the rate
// the bench achieved, the samples kept and the sequence numbers missing between them, what Fast
// DDS reported lost, the file's size.

#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "dpc/record/mcap.h"
#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

using namespace std::chrono_literals;

struct Figures {
  double cpu_percent_of_core = 0.0;
  double achieved_hz = 0.0;
  std::string samples = "–", missing = "–", lost = "–";
  double file_mb = 0.0;
  bool complete = true;
};

/// One run: a fresh bench at `rate_hz`, then `args` (a dpc command line) for `seconds` of
/// steady window after 2 s of discovery. `file` is the recording, or empty.
Figures Measure(const BusBenchmarkHarness& harness, int rate_hz, double seconds, const std::string& name,
                std::vector<std::string> args, const std::string& file) {
  Services services(harness, "_" + name);
  services.Driver();
  services.Controller("A", 0);
  services.Polarimeter({"--rate-hz", std::to_string(rate_hz)});
  std::this_thread::sleep_for(3s);  // discovery and lock
  args.insert(args.begin(), DPC_BINARY);
  args.insert(args.end(), {"--domain", std::to_string(harness.domain)});
  Process tool(args, harness.LogPath(name));
  std::this_thread::sleep_for(2s);  // the tool's discovery
  const double cpu_start_s = tool.cpu_seconds();
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const double cpu_s = tool.cpu_seconds() - cpu_start_s;
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  tool.Stop(30s);
  Figures f;
  f.cpu_percent_of_core = 100.0 * cpu_s / wall_s;
  if (file.empty()) return f;
  try {
    uint64_t first_ns = 0, last_ns = 0, count = 0;
    const auto read = record::ReadMcap(file, [&](const record::McapChannel& channel, const record::McapMessage& m) {
      if (channel.topic != "dpc_stokes_sample") return;
      if (count++ == 0) first_ns = m.log_time_ns;
      last_ns = m.log_time_ns;
    });
    if (count > 1 && last_ns > first_ns) f.achieved_hz = static_cast<double>(count - 1) * 1e9 / static_cast<double>(last_ns - first_ns);
    f.complete = read.complete;
    for (const auto& m : read.metadata) {
      if (m.name != "recording") continue;
      const auto value = [&](const char* key) { return m.values.count(key) ? m.values.at(key) : std::string("?"); };
      f.samples = value("samples");
      f.missing = value("samples_missing");
      f.lost = value("lost_reported_by_dds");
    }
    f.file_mb = static_cast<double>(std::filesystem::file_size(file)) / 1e6;
  } catch (const std::exception& e) {
    fmt::print(stderr, "  cannot read {}: {}\n", file, e.what());
  }
  return f;
}

}  // namespace

void RunRecordSection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 10.0 : 60.0;
  fmt::print("record: dpc record of a real-time bench (zstd), {:.0f} s steady window; goal at 10 kHz: "
             "no sample missing, ≤ 10 % of one core\n", seconds);
  for (const int rate_hz : {2000, 10000}) {
    const std::string all_file = harness.LogPath(fmt::format("record_all_{}", rate_hz)) + ".mcap";
    const std::string sample_file = harness.LogPath(fmt::format("record_samples_{}", rate_hz)) + ".mcap";
    struct Run {
      const char* label;
      std::string name;
      std::vector<std::string> args;
      std::string file;
    };
    const std::vector<Run> runs = {
        {"dpc record, every topic", fmt::format("record_all_{}", rate_hz), {"record", "-o", all_file}, all_file},
        {"dpc record --topics sample", fmt::format("record_samples_{}", rate_hz),
         {"record", "-o", sample_file, "--topics", "sample"}, sample_file},
        {"DDS floor: dpc topic hz sample", fmt::format("hz_{}", rate_hz),
         {"topic", "hz", "sample", "--window-s", "1"}, ""},
    };
    fmt::print("  {} Hz requested:\n", rate_hz);
    for (const Run& run : runs) {
      const Figures f = Measure(harness, rate_hz, seconds, run.name, run.args, run.file);
      if (run.file.empty()) {
        fmt::print("    {:32s} CPU {:5.1f} % of one core\n", run.label, f.cpu_percent_of_core);
      } else {
        fmt::print("    {:32s} CPU {:5.1f} % of one core; bench at {:.0f} Hz; samples {}, missing between them {}, "
                   "reported lost by DDS {}; file {:.1f} MB{}\n",
                   run.label, f.cpu_percent_of_core, f.achieved_hz, f.samples, f.missing, f.lost, f.file_mb,
                   f.complete ? "" : " (NOT complete)");
      }
      std::fflush(stdout);
    }
  }
}

}  // namespace dpc::bus_benchmark
