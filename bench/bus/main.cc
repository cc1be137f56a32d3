// dpc_bus_benchmark: the bench's figures over Fast DDS (issue 3, item 10), each beside a raw
// Fast DDS reference measured by the same harness in the same run. Starts the real services
// (build/services/dpc-*) on a loopback domain of its own, prints figures, never asserts.
//
//   dpc_bus_benchmark            full run (~20 min: 60 s per rate, a 10-minute memory run)
//   dpc_bus_benchmark --quick    the same figures from short runs (~3 min)
//
// Sections (one file each, see sections.h):
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
//   failover kill -9 of the obeyed controller with a standby, at 2 and 10 kHz: gap between the
//            last command of the killed one and the first of the standby applied by the
//            driver, the error excursion over the steady-state p99, needless switches while
//            both are alive; the raw DDS reference: kill -9 of the stronger of two
//            EXCLUSIVE-ownership writers
//   tracking real time at 10 kHz, the scrambler (kicks per bench sample, and the paper's own
//            diffusion) and a deterministic rotation at increasing
//            rates: mean error without prediction, predicting across the latency, and with
//            rate commands (--predict); the rate at which each crosses 1°
//   record   dpc record of a real-time bench at 2 and 10 kHz: the recorder's CPU (% of one
//            core), the samples it kept and those missing between them (the polarimeter's
//            sequence numbers), messages dropped, file size
//   instruments  the bench through dpc-emulator (TCP, pseudo-terminals) beside the simulated one at
//            0.5-5 kHz: rate achieved, loop latency, query → reply and command → acknowledged
//            times, periods without a reading, the highest rate each path sustains
//   memory   RSS of each service at the start and the end of a long 10 kHz run
//   security the same bench open and with DDS Security (a PKI from make-bench-pki.sh) at 2,
//            10 and 20 kHz, alternating: loop latency p50/p99, CPU of the three services per
//            sample, rate achieved, error
//   transport the same bench over the shipped UDP profile, UDP without deadlines, UDP with the
//            writers' deadlines only, SHM + UDP and SHM + UDP without deadlines at 2 and 5 kHz,
//            alternating: rate, overruns, missed state deadlines, loop latency p50/p99, CPU of
//            the three services per sample
//
// --transport shm runs every section over shared memory (the profile with an SHM descriptor
// before UDP), --transport both runs them over UDP and then over SHM, each in a process of its
// own (the bench's rate, latency and failover over both, each beside raw references on the same
// transport).
//
// The raw references' far sides are this binary again, in the internal modes --pong, --relay,
// --command-echo and --raw-owner.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "harness.h"
#include "raw_ownership.h"
#include "raw_reference.h"
#include "sections.h"

int main(int argc, char** argv) {
  namespace bench = dpc::bus_benchmark;
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
  int domain = 30;
  app.add_option("--domain", domain, "DDS domain (loopback profile)")->check(CLI::Range(0, 232));
  app.add_option("--only", only, "One section: raw,loop,rate,failover,tracking,record,instruments,memory,security,transport");
  std::string transport = "udp";
  app.add_option("--transport", transport,
                 "The profile every section runs on: udp (FASTRTPS_DEFAULT_PROFILES_FILE or the shipped "
                 "loopback profile), shm (the same with shared memory listed before UDP), or both (the "
                 "sections over each, one after the other)")
      ->check(CLI::IsMember({"udp", "shm", "both"}));
  CLI11_PARSE(app, argc, argv);

  // The internal modes: the far sides of the raw references, started by the sections.
  if (pong) return bench::RunPong(domain);
  if (relay) return bench::RunRelay(domain);
  if (command_echo) return bench::RunCommandEcho(domain);
  if (raw_owner > 0) return bench::RunRawOwner(domain, raw_owner, 10000.0);

  if (transport == "both") {
    // A process per transport: Fast DDS reads its profiles once per process.
    int failures = 0;
    for (const char* each : {"udp", "shm"}) {
      std::string command = fmt::format("'{}' --transport {} --domain {}{}", std::filesystem::read_symlink("/proc/self/exe").string(),
                                        each, domain, quick ? " --quick" : "");
      if (!only.empty()) command += " --only " + only;
      fmt::print("==== transport {} ====\n", each);
      std::fflush(stdout);
      failures += std::system(command.c_str()) != 0;
    }
    return failures == 0 ? 0 : 1;
  }

  const bench::BusBenchmarkHarness harness = bench::BusBenchmarkHarness::Create(domain, quick);
  if (transport == "shm") {
    // Before any participant: the services inherit the variable, this process's raw references
    // read it at their first participant.
    const char* current = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE");
    const std::string base = current != nullptr && *current ? current : DPC_SOURCE_DIR "/deploy/fastdds/loopback.xml";
    std::ifstream in(base);
    const std::string shm = bench::WithSharedMemory(std::string(std::istreambuf_iterator<char>(in), {}));
    if (shm.empty()) {
      fmt::print(stderr, "dpc_bus_benchmark: cannot add shared memory to {}\n", base);
      return 2;
    }
    const std::string path = harness.log_dir + "/shm.xml";
    std::ofstream(path) << shm;
    setenv("FASTRTPS_DEFAULT_PROFILES_FILE", path.c_str(), 1);
  }
  fmt::print("dpc_bus_benchmark: domain {}, transport {}, logs in {}{}\n", harness.domain,
             transport == "shm" ? "SHM + UDP" : "UDP", harness.log_dir, quick ? " (quick)" : "");
  auto want = [&](const char* section) { return only.empty() || only == section; };
  // The raw references alone only on request; the loop section measures them beside the bench.
  if (only == "raw") bench::RunRawSection(harness);
  std::fflush(stdout);  // each section's figures as they come, also into a file or pipe
  if (want("loop")) {
    bench::RunLoopSection(harness);
    std::fflush(stdout);
  }
  if (want("failover")) {
    bench::RunFailoverSection(harness);
    std::fflush(stdout);
  }
  if (want("tracking")) {
    bench::RunTrackingSection(harness);
    std::fflush(stdout);
  }
  if (want("rate")) {
    bench::RunRateSection(harness);
    std::fflush(stdout);
  }
  if (want("security")) {
    bench::RunSecuritySection(harness);
    std::fflush(stdout);
  }
  if (want("transport")) {
    bench::RunTransportSection(harness);
    std::fflush(stdout);
  }
  if (want("record")) {
    bench::RunRecordSection(harness);
    std::fflush(stdout);
  }
  if (want("instruments")) {
    bench::RunInstrumentsSection(harness);
    std::fflush(stdout);
  }
  if (want("memory")) bench::RunMemorySection(harness);
  return 0;
}
