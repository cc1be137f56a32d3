// The tracking section of dpc_bus_benchmark: real time at 10 kHz under the scrambler (kicks per
// bench sample, and the paper's own diffusion) and a deterministic rotation at increasing rates:
// the mean error without prediction, predicting across the latency, and with rate commands
// (--predict); the rate at which each crosses 1°.

#include <chrono>
#include <cmath>
#include <cstdio>
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

// The rate at which the mean error crosses 1°, interpolated linearly between the measured
// rates that bracket it (0 if even the first is above, the last rate if none is).
double OneDegreeCrossing(const std::vector<double>& rates_rad_per_s, const std::vector<double>& errors_deg) {
  if (errors_deg.empty() || !(errors_deg[0] < 1.0)) return 0.0;
  for (size_t i = 1; i < errors_deg.size(); ++i) {
    if (!(errors_deg[i] < 1.0)) {
      if (!std::isfinite(errors_deg[i])) return rates_rad_per_s[i - 1];
      const double f = (1.0 - errors_deg[i - 1]) / (errors_deg[i] - errors_deg[i - 1]);
      return rates_rad_per_s[i - 1] + f * (rates_rad_per_s[i] - rates_rad_per_s[i - 1]);
    }
  }
  return rates_rad_per_s[errors_deg.size() - 1];
}

// One table: the polarimeter on `scenario` (empty: the embedded default, the paper scrambler at
// 10 kHz) for `seconds` per run, each rate without prediction, with --predict-mode latency and
// with --predict (ramp).
void TrackingTable(const BusBenchmarkHarness& harness, double seconds, const std::string& scenario,
                   const std::vector<double>& rates_rad_per_s, bool kicks) {
  constexpr int kModes = 3;
  const char* names[kModes] = {"none", "latency", "ramp"};
  const std::vector<std::string> flags[kModes] = {
      {}, {"--predict", "--predict-mode", "latency"}, {"--predict", "--predict-mode", "ramp"}};
  std::vector<double> errors_deg[kModes];
  bool lost[kModes] = {false, false, false};
  fmt::print("  {:>10}  {:>9} {:>9} {:>9}{}   (mean error, by prediction)\n", "rate", names[0], names[1],
             names[2], kicks ? "  kick floor (D = 2)" : "");
  for (double rate_rad_per_s : rates_rad_per_s) {
    double mean_deg[kModes] = {NAN, NAN, NAN};
    for (int mode = 0; mode < kModes; ++mode) {
      if (lost[mode]) {  // the error only grows with the rate
        errors_deg[mode].push_back(NAN);
        continue;
      }
      Services services(harness);
      services.Driver();
      services.Controller("A", 0, flags[mode]);
      std::this_thread::sleep_for(500ms);
      std::vector<std::string> args = {"--rate-hz", "10000", "--run-s", fmt::format("{}", seconds),
                                       "--rate-rad-per-s", fmt::format("{}", rate_rad_per_s), "--json"};
      if (!scenario.empty()) args.insert(args.begin(), scenario);
      Process& polarimeter = services.Polarimeter(args);
      polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(seconds * 3 + 60)));
      const nlohmann::json r = LastJsonLine(polarimeter.Log());
      mean_deg[mode] =
          r.is_object() && !r["error_deg"]["mean"].is_null() ? r["error_deg"]["mean"].get<double>() : NAN;
      errors_deg[mode].push_back(mean_deg[mode]);
      if (!(mean_deg[mode] < 5.0)) lost[mode] = true;
    }
    fmt::print("  {:4.0f} rad/s  {:8.3f}° {:8.3f}° {:8.3f}°", rate_rad_per_s, mean_deg[0], mean_deg[1], mean_deg[2]);
    // What no predictor knows: the kicks over the loop delay, ≈ 0.63·σ·√D, σ = ω·dt (D = 2).
    if (kicks) fmt::print("  {:17.2f}°", 0.63 * rate_rad_per_s * 1e-4 * std::sqrt(2.0) * 180.0 / M_PI);
    fmt::print("\n");
    std::fflush(stdout);
  }
  double crossing_rad_per_s[kModes];
  for (int mode = 0; mode < kModes; ++mode) {
    crossing_rad_per_s[mode] = OneDegreeCrossing(rates_rad_per_s, errors_deg[mode]);
  }
  const double none = crossing_rad_per_s[0], latency = crossing_rad_per_s[1], ramp = crossing_rad_per_s[2];
  fmt::print("  rate tracked below 1° mean (interpolated): {:.0f} rad/s without prediction, {:.0f} rad/s "
             "predicting across the latency ({:.1f}×), {:.0f} rad/s with rate commands ({:.1f}×)\n",
             none, latency, none > 0 ? latency / none : NAN, ramp, none > 0 ? ramp / none : NAN);
}

}  // namespace

void RunTrackingSection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 3.0 : 10.0;
  fmt::print("tracking in real time at 10 kHz (rotation rate → mean error), without prediction, with\n"
             "the controller predicting across the measured latency (--predict-mode latency) and with\n"
             "rate commands the driver ramps along (--predict, mode ramp)\n");
  fmt::print(" the paper scrambler (rotation about S3 + random S2 kicks of σ = ω·dt per sample):\n");
  TrackingTable(harness, seconds, "", {20.0, 30.0, 50.0, 75.0, 100.0, 150.0, 200.0, 300.0}, true);
  fmt::print(" the paper scrambler's own diffusion (its 50-MHz kicks summed over a 100-µs sample:\n"
             " deploy/scenarios/bench_paper_diffusion.pbtxt, kick_rms_ratio 0.0141):\n");
  TrackingTable(harness, seconds, std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_paper_diffusion.pbtxt",
                {20.0, 30.0, 50.0, 100.0, 200.0, 500.0, 700.0, 1000.0}, false);
  fmt::print(" a deterministic rotation (deploy/scenarios/bench_rotation.pbtxt: no kicks):\n");
  TrackingTable(harness, seconds, std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_rotation.pbtxt",
                {20.0, 30.0, 50.0, 100.0, 200.0, 500.0, 700.0, 1000.0, 1500.0}, false);
}

}  // namespace dpc::bus_benchmark
