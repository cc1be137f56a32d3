// The shared harness of dpc_bus_benchmark (see harness.h): percentile summaries, the run's log
// directory, and the launchers of the services (paths compiled in as DPC_*_BINARY) and of this
// binary's internal modes.

#include "harness.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

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

}  // namespace dpc::bus_benchmark
