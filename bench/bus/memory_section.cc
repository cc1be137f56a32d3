// The memory section of dpc_bus_benchmark: the RSS of each service at the start and the end of
// a long 10 kHz run (goal: each under 64 MB, no growth).

#include <sys/types.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <string>
#include <thread>

#include <fmt/format.h>

#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

using namespace std::chrono_literals;

/// VmRSS of `pid` from /proc, in MB; NAN if it cannot be read.
double RssMb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return NAN;
}

}  // namespace

void RunMemorySection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 60.0 : 600.0;
  fmt::print("memory at 10 kHz for {:.0f} s (goal: each service < 64 MB RSS, no growth)\n", seconds);
  Services services(harness);
  Process& driver = services.Driver();
  Process& controller = services.Controller("A", 0);
  Process& polarimeter = services.Polarimeter({"--rate-hz", "10000"});
  std::this_thread::sleep_for(10s);
  const double start_mb[3] = {RssMb(driver.pid()), RssMb(controller.pid()), RssMb(polarimeter.pid())};
  const auto end_time = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds - 10.0);
  int waited_s = 0;
  while (std::chrono::steady_clock::now() < end_time) {
    std::this_thread::sleep_for(1s);
    if (++waited_s % 60 == 0) fmt::print(stderr, "  … {} s\n", waited_s + 10);
  }
  const double end_mb[3] = {RssMb(driver.pid()), RssMb(controller.pid()), RssMb(polarimeter.pid())};
  const char* names[3] = {"dpc-driver", "dpc-controller", "dpc-polarimeter"};
  for (int i = 0; i < 3; ++i) {
    fmt::print("  {:16s} RSS {:6.1f} MB at 10 s, {:6.1f} MB at {:.0f} s: growth {:+.2f} MB\n", names[i], start_mb[i],
               end_mb[i], seconds, end_mb[i] - start_mb[i]);
  }
}

}  // namespace dpc::bus_benchmark
