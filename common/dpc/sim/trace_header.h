#pragma once
// The `# key=value` header of a trace (TraceWriter's comment lines) that lets `dpc plot` redraw
// a run: the magic line "dpc-trace", the title (the scenario's name, the device in the paper's
// notation and in light order, the method, the loop), the activation time, the target point, the
// controls' ranges, the sample rate and the decimation. Written by `dpc sim --trace` and
// `dpc-polarimeter --trace` alike.

#include <cstdint>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/control/target.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

inline constexpr const char* kTraceMagic = "dpc-trace";

/// "paper-fig4: M = R1R3R1R3 (light: R3 R1 R3 R1), gp, model loop".
std::string TraceTitle(const ScenarioConfig& scenario, const WaveplateChain& chain);

/// The header's lines (without "# "); `producer` (e.g. "dpc-polarimeter lockstep") is recorded
/// when not empty.
std::vector<std::string> TraceHeaderLines(const ScenarioConfig& scenario, const WaveplateChain& chain,
                                          const Target& target, int64_t trace_every,
                                          const std::string& producer = "");

}  // namespace dpc
