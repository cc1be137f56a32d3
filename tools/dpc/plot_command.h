#pragma once
// `dpc plot TRACE.csv -o FIGURE.png`: draws the paper-style figure (S_out components and each
// φ_i against time) from a trace written by `dpc sim --trace`.

#include <CLI/CLI.hpp>

#include <string>

#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct PlotOptions {
  std::string trace_path;
  std::string output_path;
  std::string title;
};

CLI::App* AddPlotCommand(CLI::App& app, PlotOptions* options);
cli::ExitCode RunPlotCommand(const PlotOptions& options);

}  // namespace dpc::tools
