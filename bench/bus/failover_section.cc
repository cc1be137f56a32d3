// The failover section of dpc_bus_benchmark: kill -9 of the obeyed controller with a standby,
// the gap between the last command of the killed one and the first of the standby applied by
// the driver; beside the raw DDS reference, kill -9 of the stronger of two EXCLUSIVE-ownership
// writers.

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "dpc/bus/bus_participant.h"
#include "raw_ownership.h"
#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

using testing::Eventually;
using namespace std::chrono_literals;

/// Every WaveplateState of bench1 on the harness's domain, as the driver published it.
struct StateLog {
  std::mutex mutex;
  std::vector<msg::WaveplateState> states;
  std::unique_ptr<bus::BusParticipant> participant;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> reader;
  explicit StateLog(int domain) {
    participant = std::make_unique<bus::BusParticipant>(bus::BusOptions{domain, "dpc-bench-observer"});
    reader = participant->MakeReader<msg::WaveplateState>("bench1", [this](const msg::WaveplateState& s, const auto&) {
      std::lock_guard<std::mutex> lock(mutex);
      states.push_back(s);
    });
  }
  ~StateLog() {
    reader.reset();
    participant.reset();
  }
  size_t AppliedBy(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex);
    size_t n = 0;
    for (const auto& s : states) n += s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == id;
    return n;
  }
  size_t Count() {
    std::lock_guard<std::mutex> lock(mutex);
    return states.size();
  }
  /// From state `from` on: how often control went to `id`, and how often the driver held.
  std::pair<size_t, size_t> TurnsTo(const std::string& id, size_t from) {
    std::lock_guard<std::mutex> lock(mutex);
    size_t turns = 0, holds = 0;
    for (size_t i = std::max<size_t>(from, 1); i < states.size(); ++i) {
      const auto& before = states[i - 1];
      const auto& now = states[i];
      if (now.mode() == msg::DRIVER_ACTIVE && now.obeyed_controller_id() == id && before.obeyed_controller_id() != id) ++turns;
      if (now.mode() == msg::DRIVER_HOLDING && before.mode() == msg::DRIVER_ACTIVE) ++holds;
    }
    return {turns, holds};
  }
};

/// " 1.23 4.56 …": the gaps, in ms.
std::string GapList(const std::vector<double>& gaps_ms) {
  std::string list;
  for (double g : gaps_ms) list += fmt::format(" {:.2f}", g);
  return list;
}

}  // namespace

void RunFailoverSection(const BusBenchmarkHarness& harness) {
  const int repetitions = harness.quick ? 3 : 10;
  fmt::print("failover after kill -9 of the obeyed controller (10 kHz; must ≤ 10 ms, aim ≤ 2 ms)\n");
  std::vector<double> gaps_ms;
  size_t needless_switches = 0, needless_holds = 0;
  double both_alive_s = 0.0;
  for (int r = 0; r < repetitions; ++r) {
    StateLog log(harness.domain);
    Services services(harness, fmt::format("_failover{}", r + 1));
    services.Driver();
    Process& primary = services.Controller("primary", 10);
    services.Controller("standby", 0);
    services.Polarimeter({"--rate-hz", "10000"});
    if (!Eventually([&] { return log.AppliedBy("primary") > 500; }, 30s)) {
      fmt::print("  run {}: the primary did not take control\n", r + 1);
      continue;
    }
    // Both alive: every turn to the standby now is a needless one (and a turn back).
    const size_t from = log.Count();
    const auto both_since = std::chrono::steady_clock::now();
    Eventually([&] { return log.AppliedBy("primary") > 5500; }, 30s);
    const auto [turns, holds] = log.TurnsTo("standby", from);
    needless_switches += turns;
    needless_holds += holds;
    both_alive_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - both_since).count();
    primary.Signal(SIGKILL);
    const size_t before = log.AppliedBy("standby");
    Eventually([&] { return log.AppliedBy("standby") > before + 1000; }, 10s);
    std::lock_guard<std::mutex> lock(log.mutex);
    int64_t last_primary_ns = 0, first_standby_ns = 0;
    for (const auto& s : log.states) {
      if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "primary") {
        last_primary_ns = s.command_receive_time_ns();
      }
    }
    for (const auto& s : log.states) {
      if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "standby" &&
          s.command_receive_time_ns() > last_primary_ns) {
        first_standby_ns = s.command_receive_time_ns();
        break;
      }
    }
    if (first_standby_ns > 0) gaps_ms.push_back(static_cast<double>(first_standby_ns - last_primary_ns) * 1e-6);
  }
  std::sort(gaps_ms.begin(), gaps_ms.end());
  fmt::print("  gaps (ms):{}\n", GapList(gaps_ms));
  if (!gaps_ms.empty()) {
    fmt::print("  median {:.2f} ms, worst {:.2f} ms\n", gaps_ms[gaps_ms.size() / 2], gaps_ms.back());
  }
  fmt::print("  while both controllers were alive ({:.1f} s): {} needless turns to the standby, {} holds "
             "(the price of a short timeout on a loaded machine; each is bumpless)\n",
             both_alive_s, needless_switches, needless_holds);
  std::vector<double> raw_gaps_ms = RawFailover(harness, std::max(3, repetitions / 2));
  std::sort(raw_gaps_ms.begin(), raw_gaps_ms.end());
  fmt::print("  raw DDS reference, EXCLUSIVE ownership (20 ms deadline, 10 kHz), gaps (ms):{}\n", GapList(raw_gaps_ms));
  if (!raw_gaps_ms.empty()) {
    fmt::print("  raw median {:.2f} ms, worst {:.2f} ms\n", raw_gaps_ms[raw_gaps_ms.size() / 2], raw_gaps_ms.back());
  }
}

}  // namespace dpc::bus_benchmark
