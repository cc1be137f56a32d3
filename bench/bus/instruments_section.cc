// The instruments section of dpc_bus_benchmark: the bench through the real-instrument backends
// against dpc-emulator (its default true device, no added latency), over TCP on 127.0.0.1 and
// over pseudo-terminals, beside the simulated bench at the same requested rates. Per run: the
// rate achieved, the loop latency (sample published → the state answering it received), the
// polarimeter's query → reply and the driver's command → acknowledged times (p50/p99), the
// periods without a reading. The highest rate a path sustains is the highest requested rate it
// achieves within 5 % with under 1 % of periods lost.

#include <chrono>
#include <fstream>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

struct Figures {
  double achieved_hz = 0.0;
  double loop_p50_us = NAN, loop_p99_us = NAN;
  double query_p50_us = NAN, query_p99_us = NAN;
  double apply_p50_us = NAN, apply_p99_us = NAN;
  int64_t failed_periods = 0, periods = 0;
};

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// The emulator's start-up line (its ports and pseudo-terminals), within 10 s.
std::optional<json> EmulatorPorts(const std::string& out_path) {
  for (int i = 0; i < 500; ++i) {
    std::ifstream in(out_path);
    std::string line;
    if (std::getline(in, line) && !line.empty() && line.back() == '}') return json::parse(line, nullptr, false);
    std::this_thread::sleep_for(20ms);
  }
  return std::nullopt;
}

/// One run of `seconds` at `rate_hz`: "simulated", "tcp" or "pty".
Figures Measure(const BusBenchmarkHarness& harness, const std::string& path, int rate_hz, double seconds) {
  const std::string name = fmt::format("instruments_{}_{}", path, rate_hz);
  std::string scenario = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/emulator_epc.pbtxt";
  std::unique_ptr<Process> emulator;
  if (path != "simulated") {
    const std::string out = harness.LogPath(name + "_emulator") + ".out";
    std::vector<std::string> args = {DPC_EMULATOR_BINARY, scenario, "--tcp-port-epc", "0", "--tcp-port-polarimeter",
                                     "0", "--control-port", "0"};
    if (path == "pty") args.push_back("--pty");
    emulator = std::make_unique<Process>(args, out, harness.LogPath(name + "_emulator"));
    const std::optional<json> ports = EmulatorPorts(out);
    if (!ports || ports->is_discarded()) {
      fmt::print(stderr, "  the emulator did not start (see {})\n", harness.LogPath(name + "_emulator"));
      return {};
    }
    const auto link = [&](const char* tcp, const char* pty) {
      return path == "tcp" ? fmt::format("tcp {{ host: \"127.0.0.1\" port: {} }}", (*ports)[tcp].get<int>())
                           : fmt::format("serial {{ path: \"{}\" }}", (*ports)[pty].get<std::string>());
    };
    const std::string with_devices = harness.LogPath(name) + ".pbtxt";
    std::ofstream(with_devices) << Slurp(scenario)
                                << fmt::format("\nwaveplate_device {{ link {{ {} }} }}\npolarimeter_device {{ link {{ {} }} }}\n",
                                               link("epc_tcp", "epc_pty"), link("polarimeter_tcp", "polarimeter_pty"));
    scenario = with_devices;
  }
  Services services(harness, "_" + name);
  services.Start(DPC_DRIVER_BINARY, {scenario, "--device-record", "none"}, "driver");
  services.Controller("A", 0, {scenario});
  Process& polarimeter = services.Polarimeter({scenario, "--rate-hz", std::to_string(rate_hz), "--run-s",
                                               fmt::format("{:g}", seconds + 2), "--settle-s", "2", "--json"});
  polarimeter.Wait(std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::duration<double>(seconds + 30)));
  services.StopAll();  // the driver logs its command → acknowledged times as it stops
  Figures f;
  const std::string log = Slurp(harness.LogPath("polarimeter_" + name));
  std::string last;
  for (size_t start = 0, end; (end = log.find('\n', start)) != std::string::npos; start = end + 1) {
    if (log[start] == '{') last = log.substr(start, end - start);
  }
  const json report = json::parse(last, nullptr, false);
  if (report.is_discarded() || !report.is_object()) {
    fmt::print(stderr, "  no report from the polarimeter (see {})\n", harness.LogPath("polarimeter_" + name));
    return f;
  }
  f.achieved_hz = report["bench"]["achieved_rate_hz"].get<double>();
  const json& loop = report["bench"]["loop_latency_us"]["sample_to_state_received"];
  if (loop["count"].get<int64_t>() > 0) {
    f.loop_p50_us = loop["p50"].get<double>();
    f.loop_p99_us = loop["p99"].get<double>();
  }
  if (report.contains("instrument")) {
    const json& i = report["instrument"];
    f.failed_periods = i["failed_periods"].get<int64_t>();
    f.periods = i["readings"].get<int64_t>() + f.failed_periods;
    if (i["query_round_trip_us"]["p50"].is_number()) {
      f.query_p50_us = i["query_round_trip_us"]["p50"].get<double>();
      f.query_p99_us = i["query_round_trip_us"]["p99"].get<double>();
    }
  }
  std::smatch match;
  const std::string driver_log = Slurp(harness.LogPath("driver_" + name));
  if (std::regex_search(driver_log, match, std::regex(R"(acknowledged after p50 (\d+) µs, p99 (\d+) µs)"))) {
    f.apply_p50_us = std::stod(match[1]);
    f.apply_p99_us = std::stod(match[2]);
  }
  return f;
}

}  // namespace

void RunInstrumentsSection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 5.0 : 20.0;
  fmt::print("instruments: the bench through dpc-emulator (TCP on 127.0.0.1, pseudo-terminals) beside the simulated "
             "bench, {:.0f} s per run\n", seconds);
  fmt::print("  {:>6} {:>10} | {:>9} {:>17} | {:>17} {:>17} {:>9}\n", "asked", "path", "achieved", "loop p50/p99 µs",
             "query p50/p99 µs", "set+ack p50/p99", "no reading");
  for (const std::string path : {"simulated", "tcp", "pty"}) {
    int sustained = 0;
    for (const int rate_hz : {500, 1000, 2000, 5000}) {
      const Figures f = Measure(harness, path, rate_hz, seconds);
      const double lost = f.periods > 0 ? static_cast<double>(f.failed_periods) / static_cast<double>(f.periods) : 0.0;
      if (f.achieved_hz >= 0.95 * rate_hz && lost < 0.01) sustained = rate_hz;
      fmt::print("  {:>6} {:>10} | {:>9.0f} {:>8.0f}/{:<8.0f} | {:>8.0f}/{:<8.0f} {:>8.0f}/{:<8.0f} {:>8.2f} %\n", rate_hz,
                 path, f.achieved_hz, f.loop_p50_us, f.loop_p99_us, f.query_p50_us, f.query_p99_us, f.apply_p50_us,
                 f.apply_p99_us, 100 * lost);
      std::fflush(stdout);
    }
    fmt::print("  {}: sustains {} Hz of those asked (within 5 %, under 1 % of periods without a reading)\n", path,
               sustained);
  }
}

}  // namespace dpc::bus_benchmark
