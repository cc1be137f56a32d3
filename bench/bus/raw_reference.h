#pragma once
// The raw Fast DDS references of latency and rate: the far sides this binary runs in its
// internal modes (--pong, --relay, --command-echo), their launcher, and RawReference, the near
// side that publishes StokesSample and times the WaveplateState that comes back.

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "dpc/bus/bus_participant.h"
#include "harness.h"

namespace dpc::bus_benchmark {

/// --pong: the echo of the raw ping-pong, each StokesSample answered by a WaveplateState.
int RunPong(int domain);
/// --relay: the middle of the raw three-process chain, a controller without a law: each
/// StokesSample relayed as a WaveplateCommand.
int RunRelay(int domain);
/// --command-echo: the end of the raw chain, a driver without checks: each WaveplateCommand
/// answered by a WaveplateState that carries its arrival time.
int RunCommandEcho(int domain);

/// The far side of a raw reference on `domain`: the ping-pong's echo, or the chain's relay and
/// command echo (logs <role><log_suffix>.log).
std::vector<std::unique_ptr<Process>> StartEchoes(const BusBenchmarkHarness& harness, int domain, bool chain,
                                                       const std::string& log_suffix);

/// A raw reference, kept for several rounds so that its blocks alternate with the bench's:
/// this process publishes StokesSample and takes WaveplateState back.
///  - ping-pong (the goal's reference): one echo process (`--pong`); one hop = round trip / 2;
///  - chain (the bench's topology, three processes on two cores): a relay (`--relay`, sample →
///    command) and an echo (`--command-echo`, command → state, stamped at the command's
///    arrival); one hop = (sample published → command received) / 2, as for the bench.
class RawReference {
 public:
  RawReference(const BusBenchmarkHarness& harness, int domain, bool chain = false);
  ~RawReference();

  /// `count` pings; the hops in ns. `pace_hz` > 0: one ping per period (absolute sleeps, like
  /// the real-time polarimeter), so the processes sleep between samples as the bench's do;
  /// 0: back to back.
  std::vector<double> Run(int count, double pace_hz);

 private:
  bool chain_;
  std::vector<std::unique_ptr<Process>> children_;
  bus::BusParticipant participant_;
  std::unique_ptr<bus::Writer<msg::StokesSample>> writer_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> reader_;
  std::mutex mutex_;
  std::condition_variable answered_;
  uint64_t last_answer_ = 0;
  uint64_t sequence_ = 0;
  std::vector<double> hops_ns_;
};

}  // namespace dpc::bus_benchmark
