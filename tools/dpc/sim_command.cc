#include "sim_command.h"

#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>

#include "dpc/config/scenario_error.h"
#include "dpc/scenario_io/scenario_writer.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/loop_stability.h"
#include "dpc/sim/trace_writer.h"
#include "dpc/cli/exit_code.h"
#include "dpc/cli/run_report.h"
#include "paper_figure.h"
#include "progress_bar.h"
#include "dpc/cli/scenario_loading.h"
#include "trace_format.h"

namespace dpc::tools {
namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void OnInterrupt(int) { g_interrupted.store(true); }

class SimObserver final : public SimulationObserver {
 public:
  SimObserver(TraceWriter* trace, ProgressBar* progress) : trace_(trace), progress_(progress) {}

  void OnSample(const SampleView& s) override {
    trace_->Write(s.t_s, s.s_in, s.s_out, s.error_deg, s.phi_applied);
  }
  bool wants_samples() const override { return trace_ != nullptr; }
  bool OnProgress(int64_t done, int64_t total) override {
    progress_->Update(done, total);
    return !g_interrupted.load();
  }

 private:
  TraceWriter* trace_;
  ProgressBar* progress_;
};

}  // namespace

CLI::App* AddSimCommand(CLI::App& app, SimOptions* o) {
  CLI::App* sim = app.add_subcommand(
      "sim", "Run one closed-loop simulation (the paper's section IV experiment by default)");
  sim->add_option("scenario", o->scenario_path,
                  "Scenario in Protobuf text format (deploy/scenarios/*.pbtxt); default: the "
                  "paper's 3-stage scenario")
      ->check(CLI::ExistingFile);
  o->overrides.AddTo(*sim);
  sim->add_option("--trace", o->trace_path, "Stream a CSV trace of the run to this file");
  sim->add_option("--trace-every", o->trace_every,
                  "Keep every N-th sample in the trace (default: at most ~50k rows)")
      ->check(CLI::PositiveNumber);
  sim->add_option("--plot", o->plot_path,
                  "Draw the paper-style figure (S_out and each phi_i against time) to this PNG");
  sim->add_flag("--json", o->json, "Print one JSON object with the results");
  sim->add_flag("--progress", o->progress, "Show a progress bar (default: on a terminal)");
  sim->add_flag("--no-progress", o->no_progress, "Never show a progress bar");
  sim->add_flag("--print-scenario", o->print_scenario,
                "Print the effective scenario (after overrides) in text format and exit");
  return sim;
}

cli::ExitCode RunSimCommand(const SimOptions& o) {
  std::unique_ptr<ClosedLoopSimulator> simulator;
  try {
    ScenarioConfig scenario = cli::LoadScenarioWithOverrides(o.scenario_path, o.overrides, PaperScenario("131"));
    simulator = std::make_unique<ClosedLoopSimulator>(scenario);
  } catch (const ScenarioError& e) {
    fmt::print(stderr, "dpc sim: {}\n", cli::DescribeScenarioError(e, o.overrides));
    return cli::ExitCode::kInvalidInput;
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "dpc sim: invalid scenario: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }
  if (o.print_scenario) {
    fmt::print("{}", ScenarioToText(simulator->scenario()));
    return cli::ExitCode::kOk;
  }
  const std::vector<std::string> warnings = ScenarioWarnings(simulator->scenario());
  for (const auto& w : warnings) fmt::print(stderr, "dpc sim: warning: {}\n", w);

  // A plot needs a trace: next to the PNG unless --trace names one.
  std::string trace_path = o.trace_path;
  if (trace_path.empty() && !o.plot_path.empty()) {
    trace_path = std::filesystem::path(o.plot_path).replace_extension(".csv").string();
  }
  const int64_t total = simulator->total_samples();
  const int64_t every = o.trace_every > 0 ? o.trace_every : std::max<int64_t>(1, total / 50000);

  try {
    std::unique_ptr<TraceWriter> trace;
    if (!trace_path.empty()) {
      std::vector<std::string> names;
      for (const auto& c : simulator->chain().controls()) names.push_back(c.name);
      trace = std::make_unique<TraceWriter>(trace_path, names,
                                            TraceHeaderComments(*simulator, every));
    }
    const bool show_progress =
        !o.no_progress && !o.json && (o.progress || ProgressBar::StderrIsTerminal());
    ProgressBar progress("dpc sim", show_progress);
    SimObserver observer(trace.get(), &progress);

    g_interrupted.store(false);
    const auto previous_int = std::signal(SIGINT, OnInterrupt);
    const auto previous_term = std::signal(SIGTERM, OnInterrupt);
    const SimulationResult result = simulator->Run(&observer, every);
    std::signal(SIGINT, previous_int);
    std::signal(SIGTERM, previous_term);
    progress.Finish();
    if (trace) trace->Flush();

    if (o.json) {
      std::cout << cli::RunReportJson(cli::DescribeRun(*simulator), result, warnings).dump() << std::endl;
    } else {
      fmt::print("{}", cli::RunReportText(cli::DescribeRun(*simulator), result));
      if (trace) fmt::print("trace      {} ({} rows, every {} samples)\n", trace->path(),
                            trace->rows(), every);
    }
    if (!o.plot_path.empty()) {
      trace.reset();  // closes the file
      WritePaperFigure(trace_path, o.plot_path, FigureOptionsFor(*simulator));
      if (!o.json) fmt::print("figure     {}\n", o.plot_path);
    }
    return result.stopped_early ? cli::ExitCode::kInterrupted : cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc sim: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
