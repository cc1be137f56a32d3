// The loop section of dpc_bus_benchmark: sample published → command received at the driver (two
// hops: polarimeter → controller → driver, plus the controller's update) → state published →
// state back at the bench, lockstep then real time at 1 kHz, in rounds that alternate with both
// raw references.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "raw_reference.h"
#include "sections.h"
#include "support/json_lines.h"

namespace dpc::bus_benchmark {
namespace {

using testing::LastJsonLine;
using namespace std::chrono_literals;

/// A span of the polarimeter's bench.loop_latency_us report, in ns.
Percentiles SpanNs(const nlohmann::json& j) {
  Percentiles p;
  if (!j.is_object() || j["p50"].is_null()) return p;
  p.count = j["count"].get<size_t>();
  p.p50 = j["p50"].get<double>() * 1e3;
  p.p99 = j["p99"].get<double>() * 1e3;
  p.p999 = j["p999"].get<double>() * 1e3;
  p.max = j["max"].get<double>() * 1e3;
  return p;
}

/// The bench's hops beside the raw ones, in `rounds` alternating blocks (bench then raw, raw
/// then bench, …): on a shared VM the raw hop alone drifts by tens of percent from one minute
/// to the next, more than the difference being measured, so each ratio compares blocks run
/// seconds apart; the figures are the medians over the rounds. The bench's spans come from
/// the polarimeter's own report (bench.loop_latency_us: from the states it receives anyway),
/// so no extra observer takes a share of the two cores. `lockstep`: each sample waits for the
/// state answering the previous one (the answer to a sample and the next sample reach the
/// controller together), the raw reference back to back; otherwise real time at `rate_hz`
/// (nothing overlaps at a low rate), the raw reference paced at the same rate.
void LoopLatency(const BusBenchmarkHarness& harness, int rounds, double seconds_per_round, bool lockstep,
                 double rate_hz) {
  Services services(harness);
  services.Driver();
  services.Controller("A", 0);
  RawReference raw(harness, harness.RawDomain(1));
  RawReference chain(harness, harness.RawDomain(2), true);
  std::this_thread::sleep_for(1s);  // let the controller match the driver first
  struct Round {
    Percentiles to_driver, to_state, loop, hop, raw, chain;
    double ratio = NAN;
    double achieved_hz = NAN;
  };
  std::vector<Round> results;
  if (lockstep) {
    fmt::print("loop, lockstep, {} rounds of {:.1f} s of bench time, each beside a raw back-to-back block\n", rounds,
               seconds_per_round);
  } else {
    fmt::print("loop, real time at {:.0f} Hz, {} rounds of {:.1f} s, each beside a raw block paced at {:.0f} Hz\n",
               rate_hz, rounds, seconds_per_round, rate_hz);
  }
  for (int round = 0; round < rounds; ++round) {
    Round result;
    auto run_bench = [&] {
      const std::string seconds = fmt::format("{}", seconds_per_round);
      Process& polarimeter = services.Polarimeter(
          lockstep ? std::vector<std::string>{"--lockstep", "--duration-s", seconds, "--json"}
                   : std::vector<std::string>{"--rate-hz", fmt::format("{}", rate_hz), "--run-s", seconds, "--json"});
      polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(600)));
      const nlohmann::json report = LastJsonLine(polarimeter.Log());
      if (!report.is_object()) return;
      result.achieved_hz = report["bench"]["achieved_rate_hz"].get<double>();
      const nlohmann::json& latency = report["bench"]["loop_latency_us"];
      result.to_driver = SpanNs(latency["sample_to_command_at_driver"]);
      result.to_state = SpanNs(latency["sample_to_state_published"]);
      result.loop = SpanNs(latency["sample_to_state_received"]);
      result.hop = result.to_driver;  // two hops: half of each percentile
      for (double* v : {&result.hop.p50, &result.hop.p99, &result.hop.p999, &result.hop.max}) *v /= 2.0;
    };
    auto run_raw = [&] {
      const int count = lockstep ? std::max<int>(1000, static_cast<int>(seconds_per_round * 4000))
                                 : static_cast<int>(seconds_per_round * rate_hz);
      result.raw = Summarize(raw.Run(count, lockstep ? 0.0 : rate_hz));
      result.chain = Summarize(chain.Run(count, lockstep ? 0.0 : rate_hz));
    };
    if (round % 2 == 0) {
      run_bench();
      run_raw();
    } else {
      run_raw();
      run_bench();
    }
    result.ratio = result.hop.p50 / result.raw.p50;
    fmt::print("  round {}: per hop p50 {:6.1f} µs (n = {}), raw hop p50 {:6.1f} µs (n = {}): ratio {:.2f}; "
               "raw chain hop p50 {:6.1f} µs\n",
               round + 1, result.hop.p50 * 1e-3, result.hop.count, result.raw.p50 * 1e-3, result.raw.count,
               result.ratio, result.chain.p50 * 1e-3);
    std::fflush(stdout);
    results.push_back(result);
  }
  services.StopAll();
  // The median over the rounds of each figure.
  auto median = [&](auto field) {
    std::vector<double> v;
    for (const Round& r : results) {
      if (std::isfinite(field(r))) v.push_back(field(r));
    }
    if (v.empty()) return static_cast<double>(NAN);
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  auto medians = [&](auto member) {
    Percentiles p;
    p.p50 = median([&](const Round& r) { return (r.*member).p50; });
    p.p99 = median([&](const Round& r) { return (r.*member).p99; });
    p.p999 = median([&](const Round& r) { return (r.*member).p999; });
    for (const Round& r : results) p.count += (r.*member).count;
    return p;
  };
  const Percentiles hop = medians(&Round::hop), reference = medians(&Round::raw),
                    chained = medians(&Round::chain);
  fmt::print("  medians over the rounds:\n");
  if (lockstep) {
    fmt::print("  lockstep rate                   {:.0f} samples/s across the three processes (with the wait for "
               "the first answer)\n",
               median([](const Round& r) { return r.achieved_hz; }));
  }
  fmt::print("  sample → command at driver      {}\n", Us(medians(&Round::to_driver)));
  fmt::print("  sample → state published        {}\n", Us(medians(&Round::to_state)));
  fmt::print("  sample → state at the bench     {}\n", Us(medians(&Round::loop)));
  fmt::print("  per hop (→ driver / 2)          {}\n", Us(hop));
  fmt::print("  raw Fast DDS hop ({})   {}\n", lockstep ? "back to back" : fmt::format("paced {:.0f} Hz", rate_hz),
             Us(reference));
  fmt::print("  ratio per hop / raw hop         p50 {:.2f}  p99 {:.2f}  p99.9 {:.2f}   (goal ≤ 1.1)\n",
             hop.p50 / reference.p50, hop.p99 / reference.p99, hop.p999 / reference.p999);
  fmt::print("  raw three-process chain hop       {}\n", Us(chained));
  fmt::print("  ratio per hop / raw chain hop   p50 {:.2f}  p99 {:.2f}  p99.9 {:.2f}   (the bench's topology: "
             "sample → relay → echo, no law, no checks)\n",
             hop.p50 / chained.p50, hop.p99 / chained.p99, hop.p999 / chained.p999);
  const double median_ratio = median([](const Round& r) { return r.ratio; });
  double lowest = INFINITY, highest = -INFINITY;
  for (const Round& r : results) {
    lowest = std::min(lowest, r.ratio);
    highest = std::max(highest, r.ratio);
  }
  fmt::print("  ratio of the p50s, round by round: median {:.2f}, range {:.2f}–{:.2f}\n", median_ratio, lowest, highest);
}

}  // namespace

void RunLoopSection(const BusBenchmarkHarness& harness) {
  const int rounds = harness.quick ? 3 : 8;
  LoopLatency(harness, rounds, harness.quick ? 0.3 : 0.5, /*lockstep=*/true, 0.0);
  LoopLatency(harness, rounds, harness.quick ? 1.0 : 3.0, /*lockstep=*/false, 1000.0);
}

}  // namespace dpc::bus_benchmark
