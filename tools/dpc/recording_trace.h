#pragma once
// A recording (`dpc record`'s MCAP file) as a trace that `dpc plot` draws: one row per recorded
// polarimeter sample — time = its log time since the first sample's, S_in, S_out, the error to
// the target in force then (the latest dpc_target), φ = the latest driver state's phi_applied —
// and the figure's options: a title naming the recording, the bench and the device (from its
// device description), the target, the controls' ranges, the intervals in which the driver held
// and each switch of the obeyed controller. Every message is checked as the services check it
// (bus::Read*); one that fails is skipped and counted.

#include <cstdint>
#include <string>
#include <vector>

#include "paper_figure.h"

namespace dpc::tools {

struct RecordingFigure {
  FigureOptions options;
  uint64_t samples = 0;            ///< rows written
  uint64_t skipped = 0;            ///< messages that failed their check
  std::vector<std::string> notes;  ///< what the figure lacks and why (e.g. no driver state)
};

/// Writes the trace of `mcap_path` into `trace_csv` (TraceWriter's format). Throws
/// std::runtime_error if the file cannot be read as MCAP or holds no usable sample.
RecordingFigure WriteRecordingTrace(const std::string& mcap_path, const std::string& trace_csv);

}  // namespace dpc::tools
