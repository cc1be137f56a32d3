#pragma once
// The raw DDS reference of failover: EXCLUSIVE ownership, what DDS alone offers. Two writers
// of StokesSample (this binary's internal mode --raw-owner) and a reader that sees the weaker
// take over when the stronger is killed.

#include <vector>

#include "harness.h"

namespace dpc::bus_benchmark {

/// --raw-owner: a raw writer of StokesSample at `rate_hz` on `domain` with EXCLUSIVE ownership
/// of `strength` (the bench's writer profile otherwise: 20 ms deadline, best effort), until
/// SIGINT or SIGTERM. optical_power_w carries the strength.
int RunRawOwner(int domain, int strength, double rate_hz);

/// `repetitions` times, kill -9 of the stronger of two EXCLUSIVE writers at 10 kHz on the
/// harness's domain: the gaps (ms) at the reader between the last sample of the strong writer
/// and the first of the weak one.
std::vector<double> RawFailover(const BusBenchmarkHarness& harness, int repetitions);

}  // namespace dpc::bus_benchmark
