#pragma once
// The metadata a `dpc sim --trace` CSV carries in its comment lines, one `# key=value` each,
// so that `dpc plot` can draw a trace on its own:
//   # dpc-trace
//   # title=paper-fig3: R1 R3 R1, gp, model loop
//   # activation_s=0.002
//   # target_point=0,0.6,0.8          (point targets only)
//   # sample_rate_hz=50000000
//   # trace_every=10

#include <map>
#include <string>
#include <vector>

#include "dpc/sim/closed_loop_simulator.h"
#include "paper_figure.h"

namespace dpc::tools {

std::vector<std::string> TraceHeaderComments(const ClosedLoopSimulator& simulator,
                                             int64_t trace_every);

/// The figure options for a run of `simulator` (title, activation line, target lines).
FigureOptions FigureOptionsFor(const ClosedLoopSimulator& simulator);

/// Reads the `# key=value` lines at the top of a trace. Throws std::runtime_error if the file
/// cannot be read or is not a dpc trace.
std::map<std::string, std::string> ReadTraceMetadata(const std::string& path);

/// Figure options from trace metadata (missing keys are left unset).
FigureOptions FigureOptionsFromMetadata(const std::map<std::string, std::string>& metadata);

}  // namespace dpc::tools
