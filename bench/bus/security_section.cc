// The security section of dpc_bus_benchmark: the same bench (driver, one controller,
// polarimeter in real time) open and with DDS Security (a bench PKI made by
// deploy/security/make-bench-pki.sh: PKI-DH authentication, Access-Permissions, AES-GCM-GMAC
// as its governance says), side by side at each rate: the loop latency (sample published →
// state received at the polarimeter), the CPU time of the three services per sample, the rate
// achieved, and the error. The two modes alternate, in rounds.

#include <cstdlib>
#include <string>

#include <fmt/format.h>

#include "sections.h"

namespace dpc::bus_benchmark {

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
      const RealTimeRun open = RunRealTimeBench(harness, rate_hz, seconds, fmt::format("_open_{:.0f}_{}", rate_hz, round));
      const RealTimeRun secure = RunRealTimeBench(harness, rate_hz, seconds,
                                                  fmt::format("_secure_{:.0f}_{}", rate_hz, round),
                                                  {"--security-dir", pki});
      fmt::print("  {:5.0f} Hz  open:   {}\n", rate_hz, Row(open));
      fmt::print("  {:5.0f} Hz  secure: {}\n", rate_hz, Row(secure));
      if (open.ok && secure.ok) {
        fmt::print("  {:5.0f} Hz  cost: {}\n", rate_hz, Change(open, secure));
      }
    }
  }
}

}  // namespace dpc::bus_benchmark
