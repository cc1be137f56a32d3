// The rate section of dpc_bus_benchmark: the bench in real time at 5, 10, 15 and 20 kHz
// (overruns and missed deadlines over the run), beside raw references paced at the same rate,
// echoed by a second process and relayed through the three-process chain.

#include <sys/prctl.h>

#include <atomic>
#include <cmath>
#include <chrono>
#include <cstdint>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "raw_reference.h"
#include "sections.h"
#include "support/json_lines.h"

namespace dpc::bus_benchmark {
namespace {

using testing::LastJsonLine;
using testing::Eventually;
using namespace std::chrono_literals;

struct RawRateResult {
  double achieved_hz = 0.0;
  int64_t late_periods = 0;
  double answered_fraction = 0.0;
};

/// The raw reference for the real-time rate: StokesSample paced at `rate_hz` (absolute sleeps,
/// late periods counted as the polarimeter does), each answered by a WaveplateState from a
/// second process (`chain`: through the relay and the command echo), without waiting for the
/// answers. On the bench's own domain: the services are stopped by then.
RawRateResult RawRate(const BusBenchmarkHarness& harness, double rate_hz, double seconds, bool chain) {
  const auto echoes = StartEchoes(harness, harness.domain, chain, "_rate");
  bus::BusParticipant participant({harness.domain, "dpc-bench-rate", {}});
  auto writer = participant.MakeWriter<msg::StokesSample>("");
  std::atomic<uint64_t> answers{0};
  auto reader = participant.MakeReader<msg::WaveplateState>("", [&](const msg::WaveplateState&, const auto&) {
    answers.fetch_add(1, std::memory_order_relaxed);
  });
  Eventually([&] { return writer->matched_readers() > 0 && reader->counters().matched_writers.load() > 0; }, 20s);
  std::this_thread::sleep_for(200ms);
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  msg::StokesSample sample;
  sample.bench_id("bench1");
  sample.s_in({1, 0, 0});
  sample.s_out({1, 0, 0});
  const int64_t period_ns = static_cast<int64_t>(1e9 / rate_hz);
  const int64_t total = static_cast<int64_t>(rate_hz * seconds);
  RawRateResult result;
  const int64_t start_ns = MonotonicNs();
  int64_t next_ns = start_ns;
  for (int64_t k = 1; k <= total; ++k) {
    SleepUntilMonotonicNs(next_ns);
    const int64_t now_ns = MonotonicNs();
    if (now_ns - next_ns > period_ns) {
      result.late_periods += (now_ns - next_ns) / period_ns;
      next_ns = now_ns;
    }
    next_ns += period_ns;
    sample.sequence_number(static_cast<uint64_t>(k));
    sample.publish_time_ns(WallClockNs());
    writer->Write(sample);
  }
  const double wall_s = static_cast<double>(MonotonicNs() - start_ns) * 1e-9;
  std::this_thread::sleep_for(100ms);
  reader.reset();
  result.achieved_hz = static_cast<double>(total) / wall_s;
  result.answered_fraction = static_cast<double>(answers.load()) / static_cast<double>(total);
  return result;
}

}  // namespace

void RunRateSection(const BusBenchmarkHarness& harness) {
  const double seconds = harness.quick ? 10.0 : 60.0;
  fmt::print("real-time rate ({:.0f} s each; goal: ≥ 20 kHz held with zero missed deadlines)\n", seconds);
  for (double rate_hz : {5e3, 10e3, 15e3, 20e3}) {
    Services services(harness);
    services.Driver();
    services.Controller("A", 0);
    std::this_thread::sleep_for(500ms);
    Process& polarimeter = services.Polarimeter(
        {"--rate-hz", fmt::format("{}", rate_hz), "--run-s", fmt::format("{}", seconds), "--json"});
    polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(seconds * 3 + 60)));
    const nlohmann::json r = LastJsonLine(polarimeter.Log());
    if (!r.is_object()) {
      fmt::print("  {:6.0f} Hz: no report ({})\n", rate_hz, polarimeter.out_path().string());
      continue;
    }
    const auto& b = r["bench"];
    fmt::print("  {:6.0f} Hz: achieved {:8.1f} Hz, {} overruns (late periods), {} state deadline misses, "
               "error mean {:.3f}°\n",
               rate_hz, b["achieved_rate_hz"].get<double>(), b["overruns"].get<int64_t>(),
               b["state_deadline_misses"].get<int64_t>(),
               r["error_deg"]["mean"].is_null() ? NAN : r["error_deg"]["mean"].get<double>());
    services.StopAll();
    const RawRateResult raw = RawRate(harness, rate_hz, seconds, false);
    fmt::print("          raw DDS (sample out, echo back, same QoS): achieved {:8.1f} Hz, {} late periods, "
               "{:.1f} % echoed\n",
               raw.achieved_hz, raw.late_periods, 100.0 * raw.answered_fraction);
    const RawRateResult chain = RawRate(harness, rate_hz, seconds, true);
    fmt::print("          raw DDS chain (sample → relay → echo, three processes): achieved {:8.1f} Hz, {} late "
               "periods, {:.1f} % answered\n",
               chain.achieved_hz, chain.late_periods, 100.0 * chain.answered_fraction);
  }
}

}  // namespace dpc::bus_benchmark
