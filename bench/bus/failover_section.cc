// The failover section of dpc_bus_benchmark: kill -9 of the obeyed controller with a standby,
// the gap between the last command of the killed one and the first of the standby applied by
// the driver (a stand-in, or after the switch; both as the states were published); beside the raw DDS reference, kill -9 of the stronger of two EXCLUSIVE-ownership
// writers.

#include <signal.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "raw_ownership.h"
#include "sections.h"

namespace dpc::bus_benchmark {
namespace {

using testing::Eventually;
using namespace std::chrono_literals;

/// Every WaveplateState of bench1 on the harness's domain, as the driver published it, and the
/// output error of every sample (to the bench's default target [0, 0.6, 0.8]).
struct StateLog {
  std::mutex mutex;
  std::vector<msg::WaveplateState> states;
  std::vector<std::pair<int64_t, double>> errors_deg;  ///< (publish time, error)
  std::unique_ptr<bus::BusParticipant> participant;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> reader;
  std::unique_ptr<bus::Reader<msg::StokesSample>> samples;
  explicit StateLog(int domain) {
    participant = std::make_unique<bus::BusParticipant>(bus::BusOptions{domain, "dpc-bench-observer", {}});
    reader = participant->MakeReader<msg::WaveplateState>("bench1", [this](const msg::WaveplateState& s, const auto&) {
      std::lock_guard<std::mutex> lock(mutex);
      states.push_back(s);
    });
    samples = participant->MakeReader<msg::StokesSample>("bench1", [this](const msg::StokesSample& m, const auto&) {
      const double cosine = std::clamp(0.6 * m.s_out()[1] + 0.8 * m.s_out()[2], -1.0, 1.0);
      std::lock_guard<std::mutex> lock(mutex);
      errors_deg.emplace_back(m.publish_time_ns(), std::acos(cosine) * 180.0 / M_PI);
    });
  }
  ~StateLog() {
    samples.reset();
    reader.reset();
    participant.reset();
  }
  /// The longest pause between consecutive samples published in [from_ns, to_ns], ns.
  int64_t LongestSamplePauseNs(int64_t from_ns, int64_t to_ns) {
    std::lock_guard<std::mutex> lock(mutex);
    int64_t previous = 0, longest = 0;
    for (const auto& [t, e] : errors_deg) {
      if (t < from_ns || t > to_ns) continue;
      if (previous != 0) longest = std::max(longest, t - previous);
      previous = t;
    }
    return longest;
  }
  /// The errors of the samples published in [from_ns, to_ns), sorted.
  std::vector<double> Errors(int64_t from_ns, int64_t to_ns) {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<double> out;
    for (const auto& [t, e] : errors_deg) {
      if (t >= from_ns && t < to_ns) out.push_back(e);
    }
    std::sort(out.begin(), out.end());
    return out;
  }
  size_t AppliedBy(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex);
    size_t n = 0;
    for (const auto& s : states) n += s.answers_sample() > 0 && s.applied_controller_id().to_string() == id;
    return n;
  }
  uint64_t StandIns() {
    std::lock_guard<std::mutex> lock(mutex);
    return states.empty() ? 0 : states.back().stand_ins();
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
  for (const double rate_hz : {2000.0, 10000.0}) {
    const double period_ms = 1e3 / rate_hz;
    fmt::print("failover after kill -9 of the obeyed controller ({:.0f} kHz; goal: gap ≤ max(2 ms, 3 periods) = "
               "{:.1f} ms, error excursion ≤ the steady-state p99, needless switches ≤ 1 per minute)\n",
               rate_hz * 1e-3, std::max(2.0, 3 * period_ms));
    std::vector<double> gaps_ms, excursion_over_p99;
    std::vector<double> sample_pauses_ms;  ///< per run: the longest pause of the samples around the kill
    std::vector<double> arrivals_ms;       ///< per run: when the standby's first applied answer had arrived
    size_t needless_switches = 0, needless_holds = 0;
    uint64_t stand_ins_alive = 0;  ///< samples the primary answered late, the standby's answer applied
    double both_alive_s = 0.0;
    // Both alive for 1 s per run (quick) or 6 s (a minute over the ten runs), to count needless switches.
    const size_t warm_states = static_cast<size_t>(0.1 * rate_hz);
    const size_t alive_states = static_cast<size_t>((harness.quick ? 1.0 : 6.0) * rate_hz);
    for (int r = 0; r < repetitions; ++r) {
      StateLog log(harness.domain);
      Services services(harness, fmt::format("_failover{:.0f}_{}", rate_hz, r + 1));
      services.Driver();
      Process& primary = services.Controller("primary", 10);
      services.Controller("standby", 0);
      services.Polarimeter({"--rate-hz", fmt::format("{:.0f}", rate_hz)});
      if (!Eventually([&] { return log.AppliedBy("primary") > warm_states; }, 30s)) {
        fmt::print("  run {}: the primary did not take control\n", r + 1);
        continue;
      }
      // Both alive: every turn to the standby now is a needless one (and a turn back).
      const size_t from = log.Count();
      const uint64_t stand_ins_from = log.StandIns();
      const auto both_since = std::chrono::steady_clock::now();
      const int64_t both_since_ns = WallClockNs();
      Eventually([&] { return log.AppliedBy("primary") > warm_states + alive_states; }, 30s);
      const auto [turns, holds] = log.TurnsTo("standby", from);
      needless_switches += turns;
      needless_holds += holds;
      stand_ins_alive += log.StandIns() - stand_ins_from;
      both_alive_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - both_since).count();
      const int64_t kill_ns = WallClockNs();
      const std::vector<double> steady = log.Errors(both_since_ns, kill_ns);
      primary.Signal(SIGKILL);
      const size_t before = log.AppliedBy("standby");
      Eventually([&] { return log.AppliedBy("standby") > before + static_cast<size_t>(0.2 * rate_hz); }, 10s);
      // The gap: from the last state applying the primary's command to the first applying the
      // standby's (a stand-in or after the switch), both as published (when applied).
      int64_t last_primary_ns = 0, first_standby_ns = 0, first_standby_received_ns = 0;
      {
        std::lock_guard<std::mutex> lock(log.mutex);
        for (const auto& s : log.states) {
          if (s.answers_sample() > 0 && s.applied_controller_id().to_string() == "primary") {
            last_primary_ns = s.publish_time_ns();
          }
        }
        for (const auto& s : log.states) {
          if (s.answers_sample() > 0 && s.applied_controller_id().to_string() == "standby" &&
              s.publish_time_ns() > last_primary_ns) {
            first_standby_ns = s.publish_time_ns();
            first_standby_received_ns = s.command_receive_time_ns();
            break;
          }
        }
      }
      if (first_standby_ns == 0) continue;
      gaps_ms.push_back(static_cast<double>(first_standby_ns - last_primary_ns) * 1e-6);
      arrivals_ms.push_back(static_cast<double>(first_standby_received_ns - last_primary_ns) * 1e-6);
      sample_pauses_ms.push_back(
          static_cast<double>(log.LongestSamplePauseNs(last_primary_ns - 1'000'000, first_standby_ns)) * 1e-6);
      const std::vector<double> around = log.Errors(kill_ns, first_standby_ns + 20'000'000);
      if (!steady.empty() && !around.empty()) {
        const double p99 = steady[steady.size() * 99 / 100];
        excursion_over_p99.push_back(around.back() / p99);
      }
    }
    fmt::print("  gaps (ms), in run order:{}\n  of which the standby's first applied answer had arrived after (ms):{}\n"
               "  the longest pause of the samples from 1 ms before the primary's last state to the standby's first "
               "(ms):{}\n",
               GapList(gaps_ms), GapList(arrivals_ms), GapList(sample_pauses_ms));
    std::sort(gaps_ms.begin(), gaps_ms.end());
    std::sort(excursion_over_p99.begin(), excursion_over_p99.end());
    if (!gaps_ms.empty()) {
      fmt::print("  median {:.2f} ms, worst {:.2f} ms ({:.1f} sample periods)\n", gaps_ms[gaps_ms.size() / 2],
                 gaps_ms.back(), gaps_ms.back() / period_ms);
    }
    if (!excursion_over_p99.empty()) {
      fmt::print("  largest error from the kill to 20 ms after the switch, over the steady-state p99:{} (worst "
                 "{:.2f})\n",
                 GapList(excursion_over_p99), excursion_over_p99.back());
    }
    fmt::print("  while both controllers were alive ({:.1f} s): {} needless turns to the standby ({:.2f} per "
               "minute), {} holds, {} samples stood in for ({:.3f} % of them)\n",
               both_alive_s, needless_switches, both_alive_s > 0 ? 60.0 * needless_switches / both_alive_s : 0.0,
               needless_holds, stand_ins_alive,
               both_alive_s > 0 ? 100.0 * static_cast<double>(stand_ins_alive) / (both_alive_s * rate_hz) : 0.0);
  }
  std::vector<double> raw_gaps_ms = RawFailover(harness, std::max(3, repetitions / 2));
  std::sort(raw_gaps_ms.begin(), raw_gaps_ms.end());
  fmt::print("  raw DDS reference, EXCLUSIVE ownership (20 ms deadline, 10 kHz), gaps (ms):{}\n", GapList(raw_gaps_ms));
  if (!raw_gaps_ms.empty()) {
    fmt::print("  raw median {:.2f} ms, worst {:.2f} ms\n", raw_gaps_ms[raw_gaps_ms.size() / 2], raw_gaps_ms.back());
  }
}

}  // namespace dpc::bus_benchmark
