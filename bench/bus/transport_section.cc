// The transport section of dpc_bus_benchmark: the same real-time bench (driver, one controller,
// polarimeter) under five variants of the loopback profile, alternating in rounds, at rates the
// machine holds: UDP on 127.0.0.1 as shipped (deploy/fastdds/loopback.xml); the same without
// any DEADLINE QoS (what the deadlines cost); UDP with the deadlines of the writers only
// (readers request none: where the cost is); shared memory listed first beside UDP (same-host
// participants meet over SHM, tools of other vendors over UDP); and SHM without deadlines.
// Each row: the rate achieved, overruns, missed state deadlines, the loop latency (sample
// published → state back at the polarimeter) and the CPU time of the three services per sample.
// The variants are written into the run's log directory; the services take them through
// FASTRTPS_DEFAULT_PROFILES_FILE and, with SHM, first clean what dead processes left in /dev/shm.

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

struct Variant {
  std::string name;
  std::string path;
};

/// `xml` without its <deadline> elements (each on one line in loopback.xml): every one, or with
/// `readers_only` those of the readers (the writers still offer theirs: a reader that requests
/// none matches a writer that offers one, not the other way round).
std::string WithoutDeadlines(const std::string& xml, bool readers_only = false) {
  std::istringstream lines(xml);
  std::string out;
  bool in_reader = false;
  for (std::string line; std::getline(lines, line);) {
    if (line.find("<data_reader") != std::string::npos) in_reader = true;
    if (line.find("</data_reader>") != std::string::npos) in_reader = false;
    if ((in_reader || !readers_only) && line.find("<deadline>") != std::string::npos) continue;
    out += line + "\n";
  }
  return out;
}

/// Sets FASTRTPS_DEFAULT_PROFILES_FILE for the services started while it lives.
class ScopedProfiles {
 public:
  explicit ScopedProfiles(const std::string& path) {
    if (const char* old = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE")) old_ = old;
    setenv("FASTRTPS_DEFAULT_PROFILES_FILE", path.c_str(), 1);
  }
  ~ScopedProfiles() {
    if (old_.empty()) {
      unsetenv("FASTRTPS_DEFAULT_PROFILES_FILE");
    } else {
      setenv("FASTRTPS_DEFAULT_PROFILES_FILE", old_.c_str(), 1);
    }
  }
  ScopedProfiles(const ScopedProfiles&) = delete;
  ScopedProfiles& operator=(const ScopedProfiles&) = delete;

 private:
  std::string old_;
};

}  // namespace

std::string WithSharedMemory(std::string xml) {
  const std::string descriptors = "<transport_descriptors>";
  const std::string transports = "<userTransports>";
  const size_t d = xml.find(descriptors);
  const size_t t = xml.find(transports);
  if (d == std::string::npos || t == std::string::npos) return {};
  xml.insert(t + transports.size(), "\n          <transport_id>dpc_shm</transport_id>");
  xml.insert(d + descriptors.size(),
             "\n      <transport_descriptor>\n        <transport_id>dpc_shm</transport_id>\n"
             "        <type>SHM</type>\n      </transport_descriptor>");
  return xml;
}

void RunTransportSection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 5.0 : 20.0;
  const int rounds = harness.quick ? 1 : 3;
  const std::string shipped = std::string(DPC_SOURCE_DIR) + "/deploy/fastdds/loopback.xml";
  const std::string xml = testing::Slurp(shipped);
  const std::string shm = WithSharedMemory(xml);
  if (xml.empty() || shm.empty()) {
    fmt::print("transport: cannot read or extend {}\n", shipped);
    return;
  }
  std::vector<Variant> variants = {{"UDP (shipped)", shipped},
                                   {"UDP, no deadlines", harness.log_dir + "/udp-no-deadlines.xml"},
                                   {"UDP, writers' deadlines", harness.log_dir + "/udp-writer-deadlines.xml"},
                                   {"SHM + UDP", harness.log_dir + "/shm.xml"},
                                   {"SHM + UDP, no deadlines", harness.log_dir + "/shm-no-deadlines.xml"}};
  std::ofstream(variants[1].path) << WithoutDeadlines(xml);
  std::ofstream(variants[2].path) << WithoutDeadlines(xml, /*readers_only=*/true);
  std::ofstream(variants[3].path) << shm;
  std::ofstream(variants[4].path) << WithoutDeadlines(shm);
  fmt::print("transport: the bench over five variants of the loopback profile, {:.0f} s per run, {} round(s), "
             "alternating (profiles in {})\n",
             seconds, rounds, harness.log_dir);
  for (const double rate_hz : {2e3, 5e3}) {
    for (int round = 1; round <= rounds; ++round) {
      std::vector<RealTimeRun> runs;
      for (size_t v = 0; v < variants.size(); ++v) {
        ScopedProfiles profiles(variants[v].path);
        runs.push_back(RunRealTimeBench(harness, rate_hz, seconds, fmt::format("_transport{}_{:.0f}_{}", v, rate_hz, round)));
        fmt::print("  {:5.0f} Hz  {:24} {}\n", rate_hz, variants[v].name, Row(runs.back()));
        std::fflush(stdout);
      }
      const RealTimeRun& base = runs[0];
      for (size_t v = 1; v < runs.size(); ++v) {
        if (!base.ok || !runs[v].ok) continue;
        fmt::print("  {:5.0f} Hz  {:24} against UDP (shipped): {}\n", rate_hz, variants[v].name, Change(base, runs[v]));
      }
    }
  }
}

}  // namespace dpc::bus_benchmark
