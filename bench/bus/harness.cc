// The shared harness of dpc_bus_benchmark (see harness.h): percentile summaries, the run's log
// directory, and the launchers of the services (paths compiled in as DPC_*_BINARY) and of this
// binary's internal modes.

#include "harness.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "support/json_lines.h"

namespace dpc::bus_benchmark {

Percentiles Summarize(std::vector<double> values) {
  Percentiles p;
  p.count = values.size();
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  auto at = [&](double q) {
    return values[std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())))];
  };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.max = values.back();
  return p;
}

std::string Us(const Percentiles& p) {
  return fmt::format("p50 {:7.1f} µs  p99 {:7.1f} µs  p99.9 {:7.1f} µs  (n = {})", p.p50 * 1e-3,
                     p.p99 * 1e-3, p.p999 * 1e-3, p.count);
}

BusBenchmarkHarness BusBenchmarkHarness::Create(int domain, bool quick) {
  BusBenchmarkHarness harness;
  harness.domain = domain;
  harness.quick = quick;
  harness.log_dir =
      std::filesystem::temp_directory_path().string() + "/dpc_bus_benchmark_" + std::to_string(getpid());
  std::filesystem::create_directories(harness.log_dir);
  harness.self = std::filesystem::read_symlink("/proc/self/exe").string();
  return harness;
}

int BusBenchmarkHarness::RawDomain(int which) const {
  return domain + which <= 232 ? domain + which : domain - which;
}

std::string BusBenchmarkHarness::LogPath(const std::string& name) const { return log_dir + "/" + name + ".log"; }

std::unique_ptr<Process> BusBenchmarkHarness::StartSelf(std::vector<std::string> args,
                                                             const std::string& log_name) const {
  args.insert(args.begin(), self);
  return std::make_unique<Process>(std::move(args), LogPath(log_name));
}

Process& Services::Start(const std::string& binary, std::vector<std::string> args, const std::string& name) {
  args.insert(args.begin(), binary);
  args.insert(args.end(), {"--domain", std::to_string(harness_.domain), "--log-level", "info"});
  args.insert(args.end(), common_args_.begin(), common_args_.end());
  processes_.push_back(std::make_unique<Process>(args, harness_.LogPath(name + log_suffix_)));
  return *processes_.back();
}

Process& Services::Driver() {
  return Start(DPC_DRIVER_BINARY, {"--device-record", harness_.LogPath("driver" + log_suffix_) + ".record"}, "driver");
}

Process& Services::Controller(const std::string& id, int priority, std::vector<std::string> extra) {
  std::vector<std::string> args = {"--id", id, "--priority", std::to_string(priority)};
  args.insert(args.end(), extra.begin(), extra.end());
  return Start(DPC_CONTROLLER_BINARY, std::move(args), "controller_" + id);
}

Process& Services::Polarimeter(std::vector<std::string> args) {
  return Start(DPC_POLARIMETER_BINARY, std::move(args), "polarimeter");
}

namespace {

double Number(const nlohmann::json& value) { return value.is_number() ? value.get<double>() : NAN; }

int64_t Count(const nlohmann::json& value) { return value.is_number() ? value.get<int64_t>() : -1; }

}  // namespace

RealTimeRun RunRealTimeBench(const BusBenchmarkHarness& harness, double rate_hz, double seconds,
                             const std::string& label, std::vector<std::string> common_args) {
  using namespace std::chrono_literals;
  Services services(harness, label);
  services.AddCommonArgs(std::move(common_args));
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
  RealTimeRun run;
  const nlohmann::json report = testing::LastJsonLine(polarimeter.Log());
  if (!report.is_object()) return run;
  const auto& bench = report["bench"];
  run.ok = true;
  run.achieved_hz = Number(bench["achieved_rate_hz"]);
  run.overruns = Count(bench["overruns"]);
  run.state_deadline_misses = Count(bench["state_deadline_misses"]);
  const auto& loop = bench["loop_latency_us"]["sample_to_state_received"];
  run.loop_p50_us = Number(loop["p50"]);
  run.loop_p99_us = Number(loop["p99"]);
  run.error_mean_deg = Number(report["error_deg"]["mean"]);
  run.cpu_us_per_sample = (cpu_after - cpu_before) * 1e6 / (run.achieved_hz * elapsed_s);
  return run;
}

std::string Row(const RealTimeRun& r) {
  if (!r.ok) return "no report";
  return fmt::format("achieved {:8.1f} Hz ({} overruns, {} state deadline misses), loop p50 {:7.1f} µs p99 {:8.1f} µs, "
                     "CPU {:6.1f} µs/sample, error mean {:.2f}°",
                     r.achieved_hz, r.overruns, r.state_deadline_misses, r.loop_p50_us, r.loop_p99_us,
                     r.cpu_us_per_sample, r.error_mean_deg);
}

std::string Change(const RealTimeRun& base, const RealTimeRun& run) {
  return fmt::format("loop p50 {:+.0f} %, p99 {:+.0f} %, CPU per sample {:+.0f} %, rate {:+.1f} %",
                     100.0 * (run.loop_p50_us / base.loop_p50_us - 1.0),
                     100.0 * (run.loop_p99_us / base.loop_p99_us - 1.0),
                     100.0 * (run.cpu_us_per_sample / base.cpu_us_per_sample - 1.0),
                     100.0 * (run.achieved_hz / base.achieved_hz - 1.0));
}

}  // namespace dpc::bus_benchmark
