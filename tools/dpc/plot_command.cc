#include "plot_command.h"

#include <fmt/format.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "dpc/cli/exit_code.h"
#include "dpc/record/mcap.h"
#include "paper_figure.h"
#include "recording_trace.h"
#include "trace_format.h"

namespace dpc::tools {

CLI::App* AddPlotCommand(CLI::App& app, PlotOptions* o) {
  CLI::App* plot = app.add_subcommand(
      "plot", "Draw the paper-style figure from a trace (dpc sim --trace, dpc-polarimeter --trace) or a recording "
              "(dpc record's .mcap)");
  plot->add_option("trace", o->trace_path, "Trace CSV or recording (.mcap)")->required()->check(CLI::ExistingFile);
  plot->add_option("--trace-out", o->trace_out_path, "With a recording: keep the trace made from it (CSV)");
  plot->add_option("-o,--output", o->output_path, "PNG to write")->required();
  plot->add_option("--title", o->title, "Figure title (default: from the trace)");
  return plot;
}

namespace {

/// Removes a temporary file when it goes.
struct TemporaryFile {
  std::string path;
  ~TemporaryFile() {
    if (!path.empty()) std::remove(path.c_str());
  }
};

}  // namespace

cli::ExitCode RunPlotCommand(const PlotOptions& o) {
  try {
    if (record::IsMcapFile(o.trace_path)) {
      TemporaryFile temporary;
      std::string trace = o.trace_out_path;
      if (trace.empty()) {
        std::string pattern = (std::filesystem::temp_directory_path() / "dpc_plot_XXXXXX").string();
        const int fd = mkstemp(pattern.data());
        if (fd < 0) throw std::runtime_error("cannot create a temporary trace file");
        close(fd);
        trace = temporary.path = pattern;
      }
      RecordingFigure figure = WriteRecordingTrace(o.trace_path, trace);
      for (const std::string& note : figure.notes) fmt::print(stderr, "dpc plot: {}\n", note);
      if (figure.skipped > 0) {
        fmt::print(stderr, "dpc plot: {} messages failed their check and were left out\n", figure.skipped);
      }
      if (!o.title.empty()) figure.options.title = o.title;
      WritePaperFigure(trace, o.output_path, figure.options);
      fmt::print("figure {} ({} samples, {} holding interval{}, {} controller switch{})\n", o.output_path,
                 figure.samples, figure.options.shaded_intervals.size(),
                 figure.options.shaded_intervals.size() == 1 ? "" : "s", figure.options.events.size(),
                 figure.options.events.size() == 1 ? "" : "es");
      return cli::ExitCode::kOk;
    }
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
