// The security section of dpc_bus_benchmark: the same bench (driver, one controller,
// polarimeter in real time) open and with DDS Security (a bench PKI made by
// deploy/security/make-bench-pki.sh: PKI-DH authentication, Access-Permissions, AES-GCM-GMAC
// as its governance says), side by side at each rate: the loop latency (sample published →
// state received at the polarimeter), the CPU time of the three services per sample, the rate
// achieved, and the error. The two modes alternate, in rounds.

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sections.h"
#include "support/json_lines.h"

namespace dpc::bus_benchmark {
namespace {

using testing::LastJsonLine;
using namespace std::chrono_literals;

struct SecurityRun {
  bool ok = false;
  double achieved_hz = NAN, loop_p50_us = NAN, loop_p99_us = NAN, cpu_us_per_sample = NAN, error_mean_deg = NAN;
  int64_t overruns = 0;
};

double Number(const nlohmann::json& value) { return value.is_number() ? value.get<double>() : NAN; }

SecurityRun RunBench(const BusBenchmarkHarness& harness, const std::string& pki, double rate_hz, double seconds,
                     const std::string& label) {
  Services services(harness, label);
  if (!pki.empty()) services.AddCommonArgs({"--security-dir", pki});
  std::vector<Process*> processes = {&services.Driver(), &services.Controller("main", 0)};
  std::this_thread::sleep_for(1s);  // discovery and, when secure, the handshakes
  Process& polarimeter = services.Polarimeter({"--rate-hz", fmt::format("{}", rate_hz), "--json"});
  processes.push_back(&polarimeter);
  std::this_thread::sleep_for(2s);  // warm-up
  double cpu_before = 0.0;
  for (Process* p : processes) cpu_before += p->cpu_seconds();
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  double cpu_after = 0.0;
  for (Process* p : processes) cpu_after += p->cpu_seconds();
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  polarimeter.Stop(10s);
  SecurityRun run;
  const nlohmann::json report = LastJsonLine(polarimeter.Log());
  if (!report.is_object()) return run;
  const auto& bench = report["bench"];
  run.ok = true;
  run.achieved_hz = Number(bench["achieved_rate_hz"]);
  run.overruns = bench["overruns"].is_number() ? bench["overruns"].get<int64_t>() : -1;
  const auto& loop = bench["loop_latency_us"]["sample_to_state_received"];
  run.loop_p50_us = Number(loop["p50"]);
  run.loop_p99_us = Number(loop["p99"]);
  run.error_mean_deg = Number(report["error_deg"]["mean"]);
  run.cpu_us_per_sample = (cpu_after - cpu_before) * 1e6 / (run.achieved_hz * elapsed_s);
  return run;
}

std::string Row(const SecurityRun& r) {
  if (!r.ok) return "no report";
  return fmt::format("achieved {:8.1f} Hz ({} overruns), loop p50 {:7.1f} µs p99 {:8.1f} µs, CPU {:6.1f} µs/sample, "
                     "error mean {:.2f}°",
                     r.achieved_hz, r.overruns, r.loop_p50_us, r.loop_p99_us, r.cpu_us_per_sample, r.error_mean_deg);
}

}  // namespace

void RunSecuritySection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 5.0 : 20.0;
  const int rounds = harness.quick ? 1 : 3;
  const std::string pki = harness.log_dir + "/pki";
  const std::string make_pki = fmt::format("'{}/deploy/security/make-bench-pki.sh' --out '{}' --controllers main "
                                           ">'{}' 2>&1",
                                           DPC_SOURCE_DIR, pki, harness.LogPath("make-bench-pki"));
  if (std::system(make_pki.c_str()) != 0) {
    fmt::print("security: make-bench-pki.sh failed ({})\n", harness.LogPath("make-bench-pki"));
    return;
  }
  fmt::print("security: the bench open and with DDS Security (PKI-DH, Access-Permissions, AES-GCM-GMAC), "
             "{:.0f} s per run, {} round(s) (goal: ≤ 25 % latency overhead)\n",
             seconds, rounds);
  for (double rate_hz : {2e3, 10e3, 20e3}) {
    for (int round = 1; round <= rounds; ++round) {
      const SecurityRun open = RunBench(harness, "", rate_hz, seconds, fmt::format("_open_{:.0f}_{}", rate_hz, round));
      const SecurityRun secure =
          RunBench(harness, pki, rate_hz, seconds, fmt::format("_secure_{:.0f}_{}", rate_hz, round));
      fmt::print("  {:5.0f} Hz  open:   {}\n", rate_hz, Row(open));
      fmt::print("  {:5.0f} Hz  secure: {}\n", rate_hz, Row(secure));
      if (open.ok && secure.ok) {
        fmt::print("  {:5.0f} Hz  cost: loop p50 {:+.0f} %, p99 {:+.0f} %, CPU per sample {:+.0f} %, rate {:+.1f} %\n",
                   rate_hz, 100.0 * (secure.loop_p50_us / open.loop_p50_us - 1.0),
                   100.0 * (secure.loop_p99_us / open.loop_p99_us - 1.0),
                   100.0 * (secure.cpu_us_per_sample / open.cpu_us_per_sample - 1.0),
                   100.0 * (secure.achieved_hz / open.achieved_hz - 1.0));
      }
    }
  }
}

}  // namespace dpc::bus_benchmark
