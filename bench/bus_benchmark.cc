// dpc_bus_benchmark: the bench's figures over Fast DDS (issue 3, item 10), each beside a raw
// Fast DDS reference measured by the same harness in the same run. Starts the real services
// (build/services/dpc-*) on a loopback domain of its own, prints figures, never asserts.
//
//   dpc_bus_benchmark            full run (~20 min: 60 s per rate, a 10-minute memory run)
//   dpc_bus_benchmark --quick    the same figures from short runs (~3 min)
//
// Sections:
//   raw      (alone) the raw references: a ping-pong, StokesSample out, WaveplateState back,
//            the bench's QoS profiles, between two processes, one hop = round trip / 2; and a
//            three-process chain, sample → relay (→ command) → echo (→ state), one hop =
//            (sample → command at the echo) / 2; back to back and paced at 1 kHz
//   loop     lockstep bench, then real time at 1 kHz: sample published → command received at
//            the driver (two hops: polarimeter → controller → driver, plus the controller's
//            update), → state published, → state back at the bench (the polarimeter's own
//            report, bench.loop_latency_us); per hop = (sample → command at the driver) / 2;
//            in rounds that alternate with both raw references (back to back for lockstep,
//            paced at the same rate for real time), each on a domain of its own; medians over
//            the rounds
//   rate     real time at 5, 10, 15, 20 kHz: overruns and missed deadlines over the run; the
//            raw references: samples paced at the same rate, echoed by a second process, and
//            relayed through the three-process chain
//   failover kill -9 of the obeyed controller with a standby: gap between the last command of
//            the killed one and the first of the standby applied by the driver; the raw DDS
//            reference: kill -9 of the stronger of two EXCLUSIVE-ownership writers
//   tracking real time at 10 kHz, the scrambler (kicks per bench sample, and the paper's own
//            diffusion) and a deterministic rotation at increasing
//            rates: mean error without prediction, predicting across the latency, and with
//            rate commands (--predict); the rate at which each crosses 1°
//   memory   RSS of each service at the start and the end of a long 10 kHz run

#include <signal.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "dpc/bus/bus_participant.h"
#include "dpc/bench/clock.h"
#include "support/child_process.h"
#include "support/json_lines.h"

namespace dpc {
namespace {

using testing::ChildProcess;
using testing::WaitUntil;
using testing::LastJsonLine;
using namespace std::chrono_literals;

struct Percentiles {
  double p50 = NAN, p99 = NAN, p999 = NAN, max = NAN;
  size_t count = 0;
};

Percentiles Summarize(std::vector<double> v) {
  Percentiles p;
  p.count = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))]; };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.max = v.back();
  return p;
}

std::string Us(const Percentiles& p) {
  return fmt::format("p50 {:7.1f} µs  p99 {:7.1f} µs  p99.9 {:7.1f} µs  (n = {})", p.p50 * 1e-3,
                     p.p99 * 1e-3, p.p999 * 1e-3, p.count);
}

std::string g_dir;
int g_domain = 30;

class Services {
 public:
  /// Logs go to <g_dir>/<service><log_suffix>.log.
  explicit Services(std::string log_suffix = "") : log_suffix_(std::move(log_suffix)) {}
  ChildProcess& Start(const std::string& binary, std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), binary);
    args.insert(args.end(), {"--domain", std::to_string(g_domain), "--log-level", "info"});
    processes_.push_back(std::make_unique<ChildProcess>(args, g_dir + "/" + name + log_suffix_ + ".log"));
    return *processes_.back();
  }
  ChildProcess& Driver() { return Start(DPC_DRIVER_BINARY, {}, "driver"); }
  ChildProcess& Controller(const std::string& id, int priority, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"--id", id, "--priority", std::to_string(priority)};
    args.insert(args.end(), extra.begin(), extra.end());
    return Start(DPC_CONTROLLER_BINARY, std::move(args), "controller_" + id);
  }
  ChildProcess& Polarimeter(std::vector<std::string> args) {
    return Start(DPC_POLARIMETER_BINARY, std::move(args), "polarimeter");
  }
  void StopAll() { processes_.clear(); }

 private:
  std::string log_suffix_;
  std::vector<std::unique_ptr<ChildProcess>> processes_;
};


// ---- raw references ------------------------------------------------------------------------

void WaitForStopSignal() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  int sig = 0;
  sigwait(&set, &sig);
}

/// A process of a raw reference: each `In` received is answered by `reply`, filled by `fill`.
template <typename In, typename Out, typename Fill>
int RunEcho(const char* name, Out reply, Fill fill) {
  bus::BusParticipant participant({g_domain, name});
  auto writer = participant.MakeWriter<Out>();
  auto reader = participant.MakeReader<In>("", [&](const In& in, const auto&) {
    fill(in, &reply);
    writer->Write(reply);
  });
  WaitForStopSignal();
  reader.reset();
  return 0;
}

/// The echo of the raw ping-pong: each StokesSample answered by a WaveplateState.
int RunPong() {
  msg::WaveplateState state;
  state.phi_applied({0.0, 0.0, 0.0});
  state.saturated({false, false, false});
  return RunEcho<msg::StokesSample>("dpc-bench-pong", state, [](const msg::StokesSample& s, msg::WaveplateState* r) {
    r->bench_id(s.bench_id());
    r->answers_sample(s.sequence_number());
    r->sample_publish_time_ns(s.publish_time_ns());
  });
}

/// The middle of the raw three-process chain, a controller without a law: each StokesSample
/// relayed as a WaveplateCommand.
int RunRelay() {
  msg::WaveplateCommand command;
  command.controller_id("relay");
  command.phi({0.0, 0.0, 0.0});
  return RunEcho<msg::StokesSample>("dpc-bench-relay", command, [](const msg::StokesSample& s, msg::WaveplateCommand* c) {
    c->bench_id(s.bench_id());
    c->sequence_number(s.sequence_number());
    c->answers_sample(s.sequence_number());
    c->sample_publish_time_ns(s.publish_time_ns());
    c->publish_time_ns(WallClockNs());
  });
}

/// The end of the raw chain, a driver without checks: each WaveplateCommand answered by a
/// WaveplateState that carries its arrival time.
int RunCommandEcho() {
  msg::WaveplateState state;
  state.phi_applied({0.0, 0.0, 0.0});
  state.saturated({false, false, false});
  return RunEcho<msg::WaveplateCommand>("dpc-bench-command-echo", state,
                                        [](const msg::WaveplateCommand& c, msg::WaveplateState* r) {
                                          r->command_receive_time_ns(WallClockNs());
                                          r->bench_id(c.bench_id());
                                          r->answers_sample(c.answers_sample());
                                          r->sample_publish_time_ns(c.sample_publish_time_ns());
                                        });
}

/// The far side of a raw reference on `domain`: the ping-pong's echo, or the chain's relay and
/// command echo (logs <name><log_suffix>.log).
std::vector<std::unique_ptr<ChildProcess>> StartEchoes(const std::string& self, int domain, bool chain,
                                                       const std::string& log_suffix) {
  std::vector<std::unique_ptr<ChildProcess>> echoes;
  for (const char* role : chain ? std::vector<const char*>{"relay", "command-echo"} : std::vector<const char*>{"pong"}) {
    echoes.push_back(std::make_unique<ChildProcess>(
        std::vector<std::string>{self, std::string("--") + role, "--domain", std::to_string(domain)},
        g_dir + "/" + role + log_suffix + ".log"));
  }
  return echoes;
}

/// A raw reference, kept for several rounds so that its blocks alternate with the bench's:
/// this process publishes StokesSample and takes WaveplateState back.
///  - ping-pong (the goal's reference): one echo process (`--pong`); one hop = round trip / 2;
///  - chain (the bench's topology, three processes on two cores): a relay (`--relay`, sample →
///    command) and an echo (`--command-echo`, command → state, stamped at the command's
///    arrival); one hop = (sample published → command received) / 2, as for the bench.
class RawReference {
 public:
  RawReference(const std::string& self, int domain, bool chain = false)
      : chain_(chain), participant_({domain, chain ? "dpc-bench-chain" : "dpc-bench-ping"}) {
    children_ = StartEchoes(self, domain, chain, "");
    writer_ = participant_.MakeWriter<msg::StokesSample>();
    reader_ = participant_.MakeReader<msg::WaveplateState>("", [this](const msg::WaveplateState& s, const auto&) {
      const int64_t now = WallClockNs();
      std::lock_guard<std::mutex> lock(mutex_);
      if (s.answers_sample() > last_answer_) {
        last_answer_ = s.answers_sample();
        const int64_t span_ns = chain_ ? s.command_receive_time_ns() - s.sample_publish_time_ns()
                                       : now - s.sample_publish_time_ns();
        hops_ns_.push_back(static_cast<double>(span_ns) / 2.0);
        answered_.notify_one();
      }
    });
    // The chain is complete when a probe comes back.
    WaitUntil([&] { return writer_->matched_readers() > 0 && reader_->counters().matched_writers.load() > 0; }, 20s);
    std::this_thread::sleep_for(200ms);
    if (chain) {
      WaitUntil([&] {
        Run(1, 0.0);
        std::lock_guard<std::mutex> lock(mutex_);
        return !hops_ns_.empty();
      }, 20s);
    }
  }
  ~RawReference() { reader_.reset(); }

  /// `count` pings. `pace_hz` > 0: one ping per period (absolute
  /// sleeps, like the real-time polarimeter), so the processes sleep between samples as the
  /// bench's do; 0: back to back.
  std::vector<double> Run(int count, double pace_hz) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      hops_ns_.clear();
    }
    msg::StokesSample sample;
    sample.bench_id("bench1");
    sample.s_in({1, 0, 0});
    sample.s_out({1, 0, 0});
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
    const int64_t period_ns = pace_hz > 0.0 ? static_cast<int64_t>(1e9 / pace_hz) : 0;
    int64_t next_ns = MonotonicNs();
    for (int i = 1; i <= count; ++i) {
      if (period_ns > 0) {
        next_ns += period_ns;
        SleepUntilMonotonicNs(next_ns);
      }
      const uint64_t sequence = ++sequence_;
      sample.sequence_number(sequence);
      sample.publish_time_ns(WallClockNs());
      writer_->Write(sample);
      std::unique_lock<std::mutex> lock(mutex_);
      answered_.wait_for(lock, 100ms, [&] { return last_answer_ >= sequence; });
    }
    std::lock_guard<std::mutex> lock(mutex_);
    return hops_ns_;
  }

 private:
  bool chain_;
  std::vector<std::unique_ptr<ChildProcess>> children_;
  bus::BusParticipant participant_;
  std::unique_ptr<bus::Writer<msg::StokesSample>> writer_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> reader_;
  std::mutex mutex_;
  std::condition_variable answered_;
  uint64_t last_answer_ = 0;
  uint64_t sequence_ = 0;
  std::vector<double> hops_ns_;
};

/// The raw references' own domains (1: ping-pong, 2: chain): an echo must not answer the
/// bench's samples or another reference's.
int RawDomain(int which = 1) { return g_domain + which <= 232 ? g_domain + which : g_domain - which; }

// ---- observing the bench -------------------------------------------------------------------

struct StateLog {
  std::mutex mutex;
  std::vector<msg::WaveplateState> states;
  std::unique_ptr<bus::BusParticipant> participant;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> reader;
  StateLog() {
    participant = std::make_unique<bus::BusParticipant>(bus::BusOptions{g_domain, "dpc-bench-observer"});
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

/// The bench's hops beside the raw ones, in `rounds` alternating blocks (bench then raw, raw
/// then bench, …): on a shared VM the raw hop alone drifts by tens of percent from one minute
/// to the next, more than the difference being measured, so each ratio compares blocks run
/// seconds apart; the figures are the medians over the rounds. The bench's spans come from
/// the polarimeter's own report (bench.loop_latency_us: from the states it receives anyway),
/// so no extra observer takes a share of the two cores. `lockstep`: each sample waits for the
/// state answering the previous one (the answer to a sample and the next sample reach the
/// controller together), the raw reference back to back; otherwise real time at `rate_hz`
/// (nothing overlaps at a low rate), the raw reference paced at the same rate.
void LoopLatency(const std::string& self, int rounds, double seconds_per_round, bool lockstep, double rate_hz) {
  Services services;
  services.Driver();
  services.Controller("A", 0);
  RawReference raw(self, RawDomain(1));
  RawReference chain(self, RawDomain(2), true);
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
  auto span = [](const nlohmann::json& j) {  // a span of bench.loop_latency_us, in ns
    Percentiles p;
    if (!j.is_object() || j["p50"].is_null()) return p;
    p.count = j["count"].get<size_t>();
    p.p50 = j["p50"].get<double>() * 1e3;
    p.p99 = j["p99"].get<double>() * 1e3;
    p.p999 = j["p999"].get<double>() * 1e3;
    p.max = j["max"].get<double>() * 1e3;
    return p;
  };
  for (int round = 0; round < rounds; ++round) {
    Round result;
    auto run_bench = [&] {
      const std::string seconds = fmt::format("{}", seconds_per_round);
      ChildProcess& polarimeter = services.Polarimeter(
          lockstep ? std::vector<std::string>{"--lockstep", "--duration-s", seconds, "--json"}
                   : std::vector<std::string>{"--rate-hz", fmt::format("{}", rate_hz), "--run-s", seconds, "--json"});
      polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(600)));
      const nlohmann::json report = LastJsonLine(polarimeter.Log());
      if (!report.is_object()) return;
      result.achieved_hz = report["bench"]["achieved_rate_hz"].get<double>();
      const nlohmann::json& latency = report["bench"]["loop_latency_us"];
      result.to_driver = span(latency["sample_to_command_at_driver"]);
      result.to_state = span(latency["sample_to_state_published"]);
      result.loop = span(latency["sample_to_state_received"]);
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
  fmt::print("  raw Fast DDS hop ({})   {}\n", lockstep ? "back to back" : fmt::format("paced {:.0f} Hz", rate_hz), Us(reference));
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


struct RawRateResult {
  double achieved_hz = 0.0;
  int64_t late_periods = 0;
  double answered_fraction = 0.0;
};

/// The raw reference for the real-time rate: StokesSample paced at `rate_hz` (absolute sleeps,
/// late periods counted as the polarimeter does), each answered by a WaveplateState from a
/// second process (`chain`: through the relay and the command echo), without waiting for the
/// answers.
RawRateResult RawRate(const std::string& self, double rate_hz, double seconds, bool chain) {
  const auto echoes = StartEchoes(self, g_domain, chain, "_rate");
  bus::BusParticipant participant({g_domain, "dpc-bench-rate"});
  auto writer = participant.MakeWriter<msg::StokesSample>();
  std::atomic<uint64_t> answers{0};
  auto reader = participant.MakeReader<msg::WaveplateState>("", [&](const msg::WaveplateState&, const auto&) {
    answers.fetch_add(1, std::memory_order_relaxed);
  });
  WaitUntil([&] { return writer->matched_readers() > 0 && reader->counters().matched_writers.load() > 0; }, 20s);
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

void Rates(double seconds, const std::string& self) {
  fmt::print("real-time rate ({:.0f} s each; goal: ≥ 20 kHz held with zero missed deadlines)\n", seconds);
  for (double rate : {5e3, 10e3, 15e3, 20e3}) {
    Services services;
    services.Driver();
    ChildProcess& controller = services.Controller("A", 0);
    std::this_thread::sleep_for(500ms);
    ChildProcess& polarimeter = services.Polarimeter({"--rate-hz", fmt::format("{}", rate), "--run-s", fmt::format("{}", seconds), "--json"});
    polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(seconds * 3 + 60)));
    const nlohmann::json r = LastJsonLine(polarimeter.Log());
    (void)controller;
    if (!r.is_object()) {
      fmt::print("  {:6.0f} Hz: no report ({})\n", rate, polarimeter.log_path());
      continue;
    }
    const auto& b = r["bench"];
    fmt::print("  {:6.0f} Hz: achieved {:8.1f} Hz, {} overruns (late periods), {} state deadline misses, "
               "error mean {:.3f}°\n",
               rate, b["achieved_rate_hz"].get<double>(), b["overruns"].get<int64_t>(),
               b["state_deadline_misses"].get<int64_t>(), r["error_deg"]["mean"].is_null() ? NAN : r["error_deg"]["mean"].get<double>());
    services.StopAll();
    const RawRateResult raw = RawRate(self, rate, seconds, false);
    fmt::print("          raw DDS (sample out, echo back, same QoS): achieved {:8.1f} Hz, {} late periods, "
               "{:.1f} % echoed\n",
               raw.achieved_hz, raw.late_periods, 100.0 * raw.answered_fraction);
    const RawRateResult chain = RawRate(self, rate, seconds, true);
    fmt::print("          raw DDS chain (sample → relay → echo, three processes): achieved {:8.1f} Hz, {} late "
               "periods, {:.1f} % answered\n",
               chain.achieved_hz, chain.late_periods, 100.0 * chain.answered_fraction);
  }
}


// ---- raw DDS failover: EXCLUSIVE ownership, what DDS alone offers -------------------------

namespace fdds = eprosima::fastdds::dds;

/// A raw writer of StokesSample at `rate_hz` with EXCLUSIVE ownership of `strength` (the bench's
/// writer profile otherwise: 20 ms deadline, best effort). optical_power_w carries the strength.
int RunRawOwner(int strength, double rate_hz) {
  bus::BusParticipant participant({g_domain, "dpc-bench-owner"});
  fdds::TypeSupport type(new msg::StokesSamplePubSubType());
  type.register_type(participant.raw());
  fdds::Topic* topic = participant.raw()->create_topic("dpc_bench_owned", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::Publisher* publisher = participant.raw()->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  fdds::DataWriterQos qos;
  publisher->get_datawriter_qos_from_profile("dpc_stokes_sample.writer", qos);
  qos.ownership().kind = fdds::EXCLUSIVE_OWNERSHIP_QOS;
  qos.ownership_strength().value = static_cast<uint32_t>(strength);
  fdds::DataWriter* writer = publisher->create_datawriter(topic, qos);
  if (writer == nullptr) return 1;
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  msg::StokesSample sample;
  sample.bench_id("owned");
  sample.s_in({1, 0, 0});
  sample.s_out({1, 0, 0});
  sample.optical_power_known(true);
  sample.optical_power_w(strength);
  const int64_t period_ns = static_cast<int64_t>(1e9 / rate_hz);
  int64_t next_ns = MonotonicNs();
  const timespec poll{0, 0};
  for (uint64_t k = 1;; ++k) {
    next_ns += period_ns;
    SleepUntilMonotonicNs(next_ns);
    sample.sequence_number(k);
    sample.publish_time_ns(WallClockNs());
    writer->write(&sample);
    if ((k & 63) == 0 && sigtimedwait(&set, nullptr, &poll) > 0) break;
  }
  publisher->delete_datawriter(writer);
  return 0;
}

class OwnedReader : public fdds::DataReaderListener {
 public:
  void on_data_available(fdds::DataReader* reader) override {
    msg::StokesSample sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(mutex);
      arrivals.emplace_back(WallClockNs(), static_cast<int>(sample.optical_power_w()));
    }
  }
  std::mutex mutex;
  std::vector<std::pair<int64_t, int>> arrivals;  ///< (wall ns, writer strength)
  size_t CountFrom(int strength) {
    std::lock_guard<std::mutex> lock(mutex);
    size_t n = 0;
    for (const auto& a : arrivals) n += a.second == strength;
    return n;
  }
};

/// kill -9 of the stronger of two EXCLUSIVE writers at 10 kHz: the gap at the reader between the
/// last sample of the strong writer and the first of the weak one.
std::vector<double> RawFailover(const std::string& self, int repetitions) {
  std::vector<double> gaps_ms;
  for (int r = 0; r < repetitions; ++r) {
    bus::BusParticipant participant({g_domain, "dpc-bench-owned-reader"});
    fdds::TypeSupport type(new msg::StokesSamplePubSubType());
    type.register_type(participant.raw());
    fdds::Topic* topic = participant.raw()->create_topic("dpc_bench_owned", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    fdds::Subscriber* subscriber = participant.raw()->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::DataReaderQos qos;
    subscriber->get_datareader_qos_from_profile("dpc_stokes_sample.reader", qos);
    qos.ownership().kind = fdds::EXCLUSIVE_OWNERSHIP_QOS;
    OwnedReader listener;
    fdds::DataReader* reader = subscriber->create_datareader(topic, qos, &listener);
    {
      ChildProcess strong({self, "--raw-owner", "10", "--domain", std::to_string(g_domain)}, g_dir + "/owner_strong.log");
      ChildProcess weak({self, "--raw-owner", "1", "--domain", std::to_string(g_domain)}, g_dir + "/owner_weak.log");
      if (WaitUntil([&] { return listener.CountFrom(10) > 5000; }, 30s)) {
        strong.Signal(SIGKILL);
        WaitUntil([&] { return listener.CountFrom(1) > 1000; }, 10s);
        std::lock_guard<std::mutex> lock(listener.mutex);
        int64_t last_strong = 0, first_weak = 0;
        for (const auto& [t, s] : listener.arrivals) {
          if (s == 10) last_strong = t;
        }
        for (const auto& [t, s] : listener.arrivals) {
          if (s == 1 && t > last_strong) {
            first_weak = t;
            break;
          }
        }
        if (first_weak > 0) gaps_ms.push_back(static_cast<double>(first_weak - last_strong) * 1e-6);
      }
    }
    reader->set_listener(nullptr);
    subscriber->delete_datareader(reader);
  }
  return gaps_ms;
}

void Failover(int repetitions, const std::string& self) {
  fmt::print("failover after kill -9 of the obeyed controller (10 kHz; must ≤ 10 ms, aim ≤ 2 ms)\n");
  std::vector<double> gaps_ms;
  size_t needless_switches = 0, needless_holds = 0;
  double both_alive_s = 0.0;
  for (int r = 0; r < repetitions; ++r) {
    StateLog log;
    Services services(fmt::format("_failover{}", r + 1));
    services.Driver();
    ChildProcess& primary = services.Controller("primary", 10);
    services.Controller("standby", 0);
    services.Polarimeter({"--rate-hz", "10000"});
    if (!WaitUntil([&] { return log.AppliedBy("primary") > 500; }, 30s)) {
      fmt::print("  run {}: the primary did not take control\n", r + 1);
      continue;
    }
    // Both alive: every turn to the standby now is a needless one (and a turn back).
    const size_t from = log.Count();
    const auto both_since = std::chrono::steady_clock::now();
    WaitUntil([&] { return log.AppliedBy("primary") > 5500; }, 30s);
    const auto [turns, holds] = log.TurnsTo("standby", from);
    needless_switches += turns;
    needless_holds += holds;
    both_alive_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - both_since).count();
    primary.Signal(SIGKILL);
    const size_t before = log.AppliedBy("standby");
    WaitUntil([&] { return log.AppliedBy("standby") > before + 1000; }, 10s);
    std::lock_guard<std::mutex> lock(log.mutex);
    int64_t last_primary = 0, first_standby = 0;
    for (const auto& s : log.states) {
      if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "primary") last_primary = s.command_receive_time_ns();
    }
    for (const auto& s : log.states) {
      if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "standby" &&
          s.command_receive_time_ns() > last_primary) {
        first_standby = s.command_receive_time_ns();
        break;
      }
    }
    if (first_standby > 0) gaps_ms.push_back(static_cast<double>(first_standby - last_primary) * 1e-6);
  }
  std::sort(gaps_ms.begin(), gaps_ms.end());
  std::string list;
  for (double g : gaps_ms) list += fmt::format(" {:.2f}", g);
  fmt::print("  gaps (ms):{}\n", list);
  if (!gaps_ms.empty()) {
    fmt::print("  median {:.2f} ms, worst {:.2f} ms\n", gaps_ms[gaps_ms.size() / 2], gaps_ms.back());
  }
  fmt::print("  while both controllers were alive ({:.1f} s): {} needless turns to the standby, {} holds "
             "(the price of a short timeout on a loaded machine; each is bumpless)\n",
             both_alive_s, needless_switches, needless_holds);
  std::vector<double> raw = RawFailover(self, std::max(3, repetitions / 2));
  std::sort(raw.begin(), raw.end());
  list.clear();
  for (double g : raw) list += fmt::format(" {:.2f}", g);
  fmt::print("  raw DDS reference, EXCLUSIVE ownership (20 ms deadline, 10 kHz), gaps (ms):{}\n", list);
  if (!raw.empty()) fmt::print("  raw median {:.2f} ms, worst {:.2f} ms\n", raw[raw.size() / 2], raw.back());
}

// The rate at which the mean error crosses 1°, interpolated linearly between the measured
// rates that bracket it (0 if even the first is above, the last rate if none is).
double OneDegreeCrossing(const std::vector<double>& rates, const std::vector<double>& errors_deg) {
  if (errors_deg.empty() || !(errors_deg[0] < 1.0)) return 0.0;
  for (size_t i = 1; i < errors_deg.size(); ++i) {
    if (!(errors_deg[i] < 1.0)) {
      if (!std::isfinite(errors_deg[i])) return rates[i - 1];
      const double f = (1.0 - errors_deg[i - 1]) / (errors_deg[i] - errors_deg[i - 1]);
      return rates[i - 1] + f * (rates[i] - rates[i - 1]);
    }
  }
  return rates[errors_deg.size() - 1];
}

// One table: the polarimeter on `scenario` (empty: the embedded default, the paper scrambler at
// 10 kHz), each rate without prediction, with --predict-mode latency and with --predict (ramp).
void TrackingTable(double seconds, const std::string& scenario, const std::vector<double>& rates, bool kicks) {
  constexpr int kModes = 3;
  const char* names[kModes] = {"none", "latency", "ramp"};
  const std::vector<std::string> flags[kModes] = {
      {}, {"--predict", "--predict-mode", "latency"}, {"--predict", "--predict-mode", "ramp"}};
  std::vector<double> errors[kModes];
  bool lost[kModes] = {false, false, false};
  fmt::print("  {:>10}  {:>9} {:>9} {:>9}{}   (mean error, by prediction)\n", "rate", names[0], names[1],
             names[2], kicks ? "  kick floor (D = 2)" : "");
  for (double rate : rates) {
    double mean[kModes] = {NAN, NAN, NAN};
    for (int mode = 0; mode < kModes; ++mode) {
      if (lost[mode]) {  // the error only grows with the rate
        errors[mode].push_back(NAN);
        continue;
      }
      Services services;
      services.Driver();
      services.Controller("A", 0, flags[mode]);
      std::this_thread::sleep_for(500ms);
      std::vector<std::string> args = {"--rate-hz", "10000", "--run-s", fmt::format("{}", seconds),
                                       "--rate-rad-per-s", fmt::format("{}", rate), "--json"};
      if (!scenario.empty()) args.insert(args.begin(), scenario);
      ChildProcess& polarimeter = services.Polarimeter(args);
      polarimeter.Wait(std::chrono::seconds(static_cast<int64_t>(seconds * 3 + 60)));
      const nlohmann::json r = LastJsonLine(polarimeter.Log());
      mean[mode] = r.is_object() && !r["error_deg"]["mean"].is_null() ? r["error_deg"]["mean"].get<double>() : NAN;
      errors[mode].push_back(mean[mode]);
      if (!(mean[mode] < 5.0)) lost[mode] = true;
    }
    fmt::print("  {:4.0f} rad/s  {:8.3f}° {:8.3f}° {:8.3f}°", rate, mean[0], mean[1], mean[2]);
    // What no predictor knows: the kicks over the loop delay, ≈ 0.63·σ·√D, σ = ω·dt (D = 2).
    if (kicks) fmt::print("  {:17.2f}°", 0.63 * rate * 1e-4 * std::sqrt(2.0) * 180.0 / M_PI);
    fmt::print("\n");
    std::fflush(stdout);
  }
  double crossing[kModes];
  for (int mode = 0; mode < kModes; ++mode) crossing[mode] = OneDegreeCrossing(rates, errors[mode]);
  fmt::print("  rate tracked below 1° mean (interpolated): {:.0f} rad/s without prediction, {:.0f} rad/s "
             "predicting across the latency ({:.1f}×), {:.0f} rad/s with rate commands ({:.1f}×)\n",
             crossing[0], crossing[1], crossing[0] > 0 ? crossing[1] / crossing[0] : NAN, crossing[2],
             crossing[0] > 0 ? crossing[2] / crossing[0] : NAN);
}

void Tracking(double seconds) {
  fmt::print("tracking in real time at 10 kHz (rotation rate → mean error), without prediction, with\n"
             "the controller predicting across the measured latency (--predict-mode latency) and with\n"
             "rate commands the driver ramps along (--predict, mode ramp)\n");
  fmt::print(" the paper scrambler (rotation about S3 + random S2 kicks of σ = ω·dt per sample):\n");
  TrackingTable(seconds, "", {20.0, 30.0, 50.0, 75.0, 100.0, 150.0, 200.0, 300.0}, true);
  fmt::print(" the paper scrambler's own diffusion (its 50-MHz kicks summed over a 100-µs sample:\n"
             " deploy/scenarios/bench_paper_diffusion.pbtxt, kick_rms_ratio 0.0141):\n");
  TrackingTable(seconds, std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_paper_diffusion.pbtxt",
                {20.0, 30.0, 50.0, 100.0, 200.0, 500.0, 700.0, 1000.0}, false);
  fmt::print(" a deterministic rotation (deploy/scenarios/bench_rotation.pbtxt: no kicks):\n");
  TrackingTable(seconds, std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_rotation.pbtxt",
                {20.0, 30.0, 50.0, 100.0, 200.0, 500.0, 700.0, 1000.0, 1500.0}, false);
}

double RssMb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return NAN;
}

void Memory(double seconds) {
  fmt::print("memory at 10 kHz for {:.0f} s (goal: each service < 64 MB RSS, no growth)\n", seconds);
  Services services;
  ChildProcess& driver = services.Driver();
  ChildProcess& controller = services.Controller("A", 0);
  ChildProcess& polarimeter = services.Polarimeter({"--rate-hz", "10000"});
  std::this_thread::sleep_for(10s);
  const double start[3] = {RssMb(driver.pid()), RssMb(controller.pid()), RssMb(polarimeter.pid())};
  const auto end_time = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds - 10.0);
  int minute = 0;
  while (std::chrono::steady_clock::now() < end_time) {
    std::this_thread::sleep_for(1s);
    if (++minute % 60 == 0) fmt::print(stderr, "  … {} s\n", minute + 10);
  }
  const double end[3] = {RssMb(driver.pid()), RssMb(controller.pid()), RssMb(polarimeter.pid())};
  const char* names[3] = {"dpc-driver", "dpc-controller", "dpc-polarimeter"};
  for (int i = 0; i < 3; ++i) {
    fmt::print("  {:16s} RSS {:6.1f} MB at 10 s, {:6.1f} MB at {:.0f} s: growth {:+.2f} MB\n", names[i], start[i],
               end[i], seconds, end[i] - start[i]);
  }
}

}  // namespace
}  // namespace dpc

int main(int argc, char** argv) {
  CLI::App app{"dpc_bus_benchmark: the bench's DDS figures beside raw Fast DDS references"};
  bool quick = false, pong = false;
  std::string only;
  app.add_flag("--quick", quick, "Short runs (~3 min) instead of the full ones (~20 min)");
  app.add_flag("--pong", pong, "(internal) the echo side of the raw ping-pong");
  bool relay = false, command_echo = false;
  app.add_flag("--relay", relay, "(internal) the middle of the raw chain: sample → command");
  app.add_flag("--command-echo", command_echo, "(internal) the end of the raw chain: command → state");
  int raw_owner = 0;
  app.add_option("--raw-owner", raw_owner, "(internal) a raw EXCLUSIVE writer of this strength");
  app.add_option("--domain", dpc::g_domain, "DDS domain (loopback profile)")->check(CLI::Range(0, 232));
  app.add_option("--only", only, "One section: raw,loop,rate,failover,tracking,memory");
  CLI11_PARSE(app, argc, argv);
  if (pong) return dpc::RunPong();
  if (relay) return dpc::RunRelay();
  if (command_echo) return dpc::RunCommandEcho();
  if (raw_owner > 0) return dpc::RunRawOwner(raw_owner, 10000.0);
  dpc::g_dir = std::filesystem::temp_directory_path().string() + "/dpc_bus_benchmark_" + std::to_string(getpid());
  std::filesystem::create_directories(dpc::g_dir);
  fmt::print("dpc_bus_benchmark: domain {}, logs in {}{}\n", dpc::g_domain, dpc::g_dir, quick ? " (quick)" : "");
  auto want = [&](const char* s) { return only.empty() || only == s; };
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  if (only == "raw") {  // the references alone; the loop section measures them beside the bench
    dpc::RawReference raw(self, dpc::RawDomain(1));
    fmt::print("raw Fast DDS ping-pong (StokesSample → WaveplateState, bench QoS), one hop:\n");
    fmt::print("  back to back                    {}\n", dpc::Us(dpc::Summarize(raw.Run(quick ? 3000 : 20000, 0.0))));
    fmt::print("  paced at 1 kHz                  {}\n", dpc::Us(dpc::Summarize(raw.Run(quick ? 3000 : 20000, 1000.0))));
    dpc::RawReference chain(self, dpc::RawDomain(2), true);
    fmt::print("raw three-process chain (sample → relay → command echo), one hop = (→ echo) / 2:\n");
    fmt::print("  back to back                    {}\n", dpc::Us(dpc::Summarize(chain.Run(quick ? 3000 : 20000, 0.0))));
    fmt::print("  paced at 1 kHz                  {}\n", dpc::Us(dpc::Summarize(chain.Run(quick ? 3000 : 20000, 1000.0))));
  }
  std::fflush(stdout);  // each section's figures as they come, also into a file or pipe
  if (want("loop")) {
    dpc::LoopLatency(self, quick ? 3 : 8, quick ? 0.3 : 0.5, true, 0.0);
    dpc::LoopLatency(self, quick ? 3 : 8, quick ? 1.0 : 3.0, false, 1000.0);
    std::fflush(stdout);
  }
  if (want("failover")) {
    dpc::Failover(quick ? 3 : 10, self);
    std::fflush(stdout);
  }
  if (want("tracking")) {
    dpc::Tracking(quick ? 3.0 : 10.0);
    std::fflush(stdout);
  }
  if (want("rate")) {
    dpc::Rates(quick ? 10.0 : 60.0, self);
    std::fflush(stdout);
  }
  if (want("memory")) dpc::Memory(quick ? 60.0 : 600.0);
  return 0;
}
