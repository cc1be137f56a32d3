// The raw Fast DDS references of latency and rate (see raw_reference.h): the echo processes,
// each a bare participant with the bench's QoS, and the near side that times their answers.

#include "raw_reference.h"

#include <signal.h>
#include <sys/prctl.h>

#include <chrono>
#include <thread>

#include "dpc/bench/clock.h"

namespace dpc::bus_benchmark {
namespace {

using testing::Eventually;
using namespace std::chrono_literals;

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
int RunEcho(int domain, const char* name, Out reply, Fill fill) {
  bus::BusParticipant participant({domain, name, {}});
  auto writer = participant.MakeWriter<Out>("");
  auto reader = participant.MakeReader<In>("", [&](const In& in, const auto&) {
    fill(in, &reply);
    writer->Write(reply);
  });
  WaitForStopSignal();
  reader.reset();
  return 0;
}

}  // namespace

int RunPong(int domain) {
  msg::WaveplateState state;
  state.phi_applied({0.0, 0.0, 0.0});
  state.saturated({false, false, false});
  return RunEcho<msg::StokesSample>(domain, "dpc-bench-pong", state,
                                    [](const msg::StokesSample& s, msg::WaveplateState* r) {
                                      r->bench_id(s.bench_id());
                                      r->answers_sample(s.sequence_number());
                                      r->sample_publish_time_ns(s.publish_time_ns());
                                    });
}

int RunRelay(int domain) {
  msg::WaveplateCommand command;
  command.controller_id("relay");
  command.phi({0.0, 0.0, 0.0});
  return RunEcho<msg::StokesSample>(domain, "dpc-bench-relay", command,
                                    [](const msg::StokesSample& s, msg::WaveplateCommand* c) {
                                      c->bench_id(s.bench_id());
                                      c->sequence_number(s.sequence_number());
                                      c->answers_sample(s.sequence_number());
                                      c->sample_publish_time_ns(s.publish_time_ns());
                                      c->publish_time_ns(WallClockNs());
                                    });
}

int RunCommandEcho(int domain) {
  msg::WaveplateState state;
  state.phi_applied({0.0, 0.0, 0.0});
  state.saturated({false, false, false});
  return RunEcho<msg::WaveplateCommand>(domain, "dpc-bench-command-echo", state,
                                        [](const msg::WaveplateCommand& c, msg::WaveplateState* r) {
                                          r->command_receive_time_ns(WallClockNs());
                                          r->bench_id(c.bench_id());
                                          r->answers_sample(c.answers_sample());
                                          r->sample_publish_time_ns(c.sample_publish_time_ns());
                                        });
}

std::vector<std::unique_ptr<Process>> StartEchoes(const BusBenchmarkHarness& harness, int domain, bool chain,
                                                       const std::string& log_suffix) {
  std::vector<std::unique_ptr<Process>> echoes;
  for (const char* role : chain ? std::vector<const char*>{"relay", "command-echo"} : std::vector<const char*>{"pong"}) {
    echoes.push_back(
        harness.StartSelf({std::string("--") + role, "--domain", std::to_string(domain)}, role + log_suffix));
  }
  return echoes;
}

RawReference::RawReference(const BusBenchmarkHarness& harness, int domain, bool chain)
    : chain_(chain), participant_({domain, chain ? "dpc-bench-chain" : "dpc-bench-ping", {}}) {
  children_ = StartEchoes(harness, domain, chain, "");
  writer_ = participant_.MakeWriter<msg::StokesSample>("");
  reader_ = participant_.MakeReader<msg::WaveplateState>("", [this](const msg::WaveplateState& s, const auto&) {
    const int64_t now_ns = WallClockNs();
    std::lock_guard<std::mutex> lock(mutex_);
    if (s.answers_sample() > last_answer_) {
      last_answer_ = s.answers_sample();
      const int64_t span_ns = chain_ ? s.command_receive_time_ns() - s.sample_publish_time_ns()
                                     : now_ns - s.sample_publish_time_ns();
      hops_ns_.push_back(static_cast<double>(span_ns) / 2.0);
      answered_.notify_one();
    }
  });
  // The chain is complete when a probe comes back.
  Eventually([&] { return writer_->matched_readers() > 0 && reader_->counters().matched_writers.load() > 0; }, 20s);
  std::this_thread::sleep_for(200ms);
  if (chain) {
    Eventually(
        [&] {
          Run(1, 0.0);
          std::lock_guard<std::mutex> lock(mutex_);
          return !hops_ns_.empty();
        },
        20s);
  }
}

RawReference::~RawReference() { reader_.reset(); }

std::vector<double> RawReference::Run(int count, double pace_hz) {
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

}  // namespace dpc::bus_benchmark
