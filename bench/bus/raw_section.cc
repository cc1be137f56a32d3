// The raw section of dpc_bus_benchmark: the raw references alone (the loop section measures
// them again, beside the bench).

#include <fmt/format.h>

#include "raw_reference.h"
#include "sections.h"

namespace dpc::bus_benchmark {

void RunRawSection(const BusBenchmarkHarness& harness) {
  const int pings = harness.quick ? 3000 : 20000;
  RawReference raw(harness, harness.RawDomain(1));
  fmt::print("raw Fast DDS ping-pong (StokesSample → WaveplateState, bench QoS), one hop:\n");
  fmt::print("  back to back                    {}\n", Us(Summarize(raw.Run(pings, 0.0))));
  fmt::print("  paced at 1 kHz                  {}\n", Us(Summarize(raw.Run(pings, 1000.0))));
  RawReference chain(harness, harness.RawDomain(2), true);
  fmt::print("raw three-process chain (sample → relay → command echo), one hop = (→ echo) / 2:\n");
  fmt::print("  back to back                    {}\n", Us(Summarize(chain.Run(pings, 0.0))));
  fmt::print("  paced at 1 kHz                  {}\n", Us(Summarize(chain.Run(pings, 1000.0))));
}

}  // namespace dpc::bus_benchmark
