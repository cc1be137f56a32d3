#pragma once
// The sections of dpc_bus_benchmark, one file each: each prints its figures to stdout, takes
// its run lengths from harness.quick and never asserts.

#include <string>

#include "harness.h"

namespace dpc::bus_benchmark {

/// raw: the raw references alone, ping-pong and three-process chain, back to back and paced at
/// 1 kHz (raw_section.cc).
void RunRawSection(const BusBenchmarkHarness& harness);
/// loop: the bench's loop latency, lockstep then real time at 1 kHz, in rounds beside both raw
/// references (loop_section.cc).
void RunLoopSection(const BusBenchmarkHarness& harness);
/// rate: real time at 5 to 20 kHz, overruns and missed deadlines, beside raw paced references
/// (rate_section.cc).
void RunRateSection(const BusBenchmarkHarness& harness);
/// failover: kill -9 of the obeyed controller with a standby, beside raw EXCLUSIVE ownership
/// (failover_section.cc).
void RunFailoverSection(const BusBenchmarkHarness& harness);
/// tracking: mean error against the rotation rate, with and without prediction
/// (tracking_section.cc).
void RunTrackingSection(const BusBenchmarkHarness& harness);
/// security: the same bench open and with DDS Security (PKI-DH, Access-Permissions,
/// AES-GCM-GMAC) side by side: loop latency, CPU per sample, sustained rate
/// (security_section.cc).
void RunSecuritySection(const BusBenchmarkHarness& harness);
/// transport: the bench over the shipped UDP profile, without deadlines, with the writers'
/// deadlines only, over SHM, and over SHM without deadlines, side by side: rate, loop latency,
/// CPU per sample (transport_section.cc).
void RunTransportSection(const BusBenchmarkHarness& harness);
/// `xml` (a loopback profile) with a shared-memory transport descriptor listed before the UDP
/// one ("" if it has no transports to extend).
std::string WithSharedMemory(std::string xml);
/// record: `dpc record` of a real-time bench at 2 and 10 kHz: the recorder's CPU, samples kept
/// and missing (record_section.cc).
void RunRecordSection(const BusBenchmarkHarness& harness);
/// instruments: the bench through dpc-emulator over TCP and pseudo-terminals beside the
/// simulated bench: rate, loop latency, query and set+ack times, the highest sustained rate
/// (instruments_section.cc).
void RunInstrumentsSection(const BusBenchmarkHarness& harness);
/// memory: RSS of each service at the start and the end of a long 10 kHz run
/// (memory_section.cc).
void RunMemorySection(const BusBenchmarkHarness& harness);

}  // namespace dpc::bus_benchmark
