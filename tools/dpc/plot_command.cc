#include "plot_command.h"

#include <fmt/format.h>

#include "dpc/cli/exit_code.h"
#include "paper_figure.h"
#include "trace_format.h"

namespace dpc::tools {

CLI::App* AddPlotCommand(CLI::App& app, PlotOptions* o) {
  CLI::App* plot = app.add_subcommand(
      "plot", "Draw the paper-style figure from a trace written by dpc sim --trace");
  plot->add_option("trace", o->trace_path, "Trace CSV")->required()->check(CLI::ExistingFile);
  plot->add_option("-o,--output", o->output_path, "PNG to write")->required();
  plot->add_option("--title", o->title, "Figure title (default: from the trace)");
  return plot;
}

cli::ExitCode RunPlotCommand(const PlotOptions& o) {
  try {
    FigureOptions options = FigureOptionsFromMetadata(ReadTraceMetadata(o.trace_path));
    if (!o.title.empty()) options.title = o.title;
    WritePaperFigure(o.trace_path, o.output_path, options);
    fmt::print("figure {}\n", o.output_path);
    return cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc plot: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
