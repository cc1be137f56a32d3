#pragma once
// `dpc plot TRACE.csv -o FIGURE.png`: draws the paper-style figure (S_out components and each
// φ_i against time) from a trace written by `dpc sim --trace`.

#include <CLI/CLI.hpp>

#include <string>

namespace dpc::tools {

struct PlotOptions {
  std::string trace_path;
  std::string output_path;
  std::string title;
};

CLI::App* AddPlotCommand(CLI::App& app, PlotOptions* options);
int RunPlotCommand(const PlotOptions& options);

}  // namespace dpc::tools
