#pragma once
// `dpc plot TRACE.csv -o FIGURE.png`: draws the paper-style figure (S_out components, the error
// and each φ_i against time) from a trace written by `dpc sim --trace` or `dpc-polarimeter
// --trace`, or from a recording (`dpc record`'s MCAP file, recognised by its magic): then the
// driver's holding intervals are shaded and each switch of the obeyed controller marked
// (recording_trace.h). `--trace-out` keeps the trace made from a recording.

#include <CLI/CLI.hpp>

#include <string>

#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct PlotOptions {
  std::string trace_path;
  std::string output_path;
  std::string title;
  std::string trace_out_path;  ///< a recording's trace, kept here (else a temporary file)
};

CLI::App* AddPlotCommand(CLI::App& app, PlotOptions* options);
cli::ExitCode RunPlotCommand(const PlotOptions& options);

}  // namespace dpc::tools
