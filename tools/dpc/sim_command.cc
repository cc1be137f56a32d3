#include "sim_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <atomic>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "dpc/config/scenario_error.h"
#include "dpc/scenario_io/scenario_writer.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/loop_stability.h"
#include "dpc/sim/sweep_runner.h"
#include "dpc/sim/trace_writer.h"
#include "dpc/cli/command_line.h"
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

/// Mean, sample standard deviation, min and max of one figure over the seeds' runs.
struct Spread {
  double mean = NAN, sd = NAN, min = NAN, max = NAN;
};

Spread SpreadOf(const std::vector<double>& values) {
  Spread s;
  if (values.empty()) return s;
  double sum = 0.0;
  s.min = s.max = values.front();
  for (double v : values) {
    sum += v;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
  }
  s.mean = sum / static_cast<double>(values.size());
  double squares = 0.0;
  for (double v : values) squares += (v - s.mean) * (v - s.mean);
  s.sd = values.size() > 1 ? std::sqrt(squares / static_cast<double>(values.size() - 1)) : 0.0;
  return s;
}

nlohmann::ordered_json SpreadJson(const Spread& s) {
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(); };
  return {{"mean", number(s.mean)}, {"sd", number(s.sd)}, {"min", number(s.min)}, {"max", number(s.max)}};
}

/// `dpc sim --seeds`: the scenario once per seed, on every core (RunSweep), each run's summary
/// and the spread over the seeds.
cli::ExitCode RunSeeds(const SimOptions& o, const ScenarioConfig& base, const std::vector<std::string>& warnings) {
  std::vector<uint64_t> seeds;
  try {
    seeds = cli::ParseSeedList(o.seeds);
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "dpc sim: --seeds: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }
  std::vector<ScenarioConfig> scenarios;
  for (uint64_t seed : seeds) {
    scenarios.push_back(base);
    scenarios.back().simulation.seed = seed;
  }
  const bool show_progress = !o.no_progress && !o.json && (o.progress || ProgressBar::StderrIsTerminal());
  ProgressBar progress("dpc sim", show_progress);
  g_interrupted.store(false);
  const auto previous_int = std::signal(SIGINT, OnInterrupt);
  const auto previous_term = std::signal(SIGTERM, OnInterrupt);
  const auto sweep_start = std::chrono::steady_clock::now();
  const std::vector<SweepOutcome> outcomes = RunSweep(
      scenarios, 0,
      [&](size_t done, size_t total) { progress.Update(static_cast<int64_t>(done), static_cast<int64_t>(total)); },
      &g_interrupted);
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  progress.Finish();
  fmt::print(stderr, "dpc sim: {}\n",
             cli::DescribeSweepSpeed(outcomes, 0, std::chrono::duration<double>(
                                                      std::chrono::steady_clock::now() - sweep_start)
                                                      .count()));

  // The figures compared over seeds: name, unit, and how to read them from a run.
  struct Figure {
    const char* name;
    const char* text_unit;  ///< in the text, the value × text_scale
    double text_scale;
    double (*of)(const RunSummary&);
  };
  static constexpr Figure kFigures[] = {
      {"error_deg_mean", "°", 1.0, [](const RunSummary& r) { return r.error_deg.mean; }},
      {"error_deg_p99", "°", 1.0, [](const RunSummary& r) { return r.error_deg.p99; }},
      {"error_deg_max", "°", 1.0, [](const RunSummary& r) { return r.error_deg.max; }},
      {"extinction_db_mean", " dB", 1.0, [](const RunSummary& r) { return r.extinction_db_mean; }},
      {"first_lock_time_s", " ms", 1e3, [](const RunSummary& r) { return r.first_lock_time_s.value_or(NAN); }},
      {"excursions", "", 1.0, [](const RunSummary& r) { return static_cast<double>(r.excursions); }},
  };
  std::vector<std::vector<double>> values(std::size(kFigures));
  nlohmann::ordered_json runs = nlohmann::ordered_json::array();
  std::string lines;
  size_t failed = 0, skipped = 0;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const SweepOutcome& outcome = outcomes[i];
    if (!outcome.ok) {
      if (outcome.error == "skipped") {
        ++skipped;
      } else {
        ++failed;
        fmt::print(stderr, "dpc sim: seed {}: {}\n", seeds[i], outcome.error);
      }
      continue;
    }
    const RunSummary& r = outcome.result.summary;
    for (size_t f = 0; f < std::size(kFigures); ++f) {
      const double v = kFigures[f].of(r);
      if (std::isfinite(v)) values[f].push_back(v);
    }
    if (o.json) {
      const ClosedLoopSimulator simulator(scenarios[i]);
      runs.push_back(cli::RunReportJson(cli::DescribeRun(simulator), outcome.result, {}));
    } else {
      lines += fmt::format("seed {:<6} error mean {:.4f}°  p99 {:.4f}°  max {:.4f}°  extinction {:.2f} dB  "
                           "first lock {}  {} excursions{}\n",
                           seeds[i], r.error_deg.mean, r.error_deg.p99, r.error_deg.max, r.extinction_db_mean,
                           r.first_lock_time_s ? fmt::format("{:.4g} ms", *r.first_lock_time_s * 1e3) : "never",
                           r.excursions, outcome.result.stopped_early ? " (stopped early)" : "");
    }
  }
  const size_t done = outcomes.size() - failed - skipped;
  if (o.json) {
    nlohmann::ordered_json over = nlohmann::ordered_json::object();
    for (size_t f = 0; f < std::size(kFigures); ++f) over[kFigures[f].name] = SpreadJson(SpreadOf(values[f]));
    nlohmann::ordered_json j;
    j["seeds"] = seeds;
    j["runs_completed"] = done;
    j["over_seeds"] = over;
    j["runs"] = runs;
    j["warnings"] = warnings;
    std::cout << j.dump() << std::endl;
  } else {
    const ClosedLoopSimulator first(scenarios.front());
    const cli::RunDescription description = cli::DescribeRun(first);
    fmt::print("scenario   {} — {} ({} controls), method {}, {} seeds\n{}", base.name, description.device,
               description.controls, MethodName(base.controller.method), seeds.size(), lines);
    fmt::print("over {} seed{} (mean ± standard deviation, min – max):\n", done, done == 1 ? "" : "s");
    for (size_t f = 0; f < std::size(kFigures); ++f) {
      const Spread s = SpreadOf(values[f]);
      const double k = kFigures[f].text_scale;
      fmt::print("  {:<20} {:.4g} ± {:.2g}{}  ({:.4g} – {:.4g}){}\n", kFigures[f].name, s.mean * k, s.sd * k,
                 kFigures[f].text_unit, s.min * k, s.max * k, values[f].size() < done ? fmt::format(", {} runs without it", done - values[f].size()) : "");
    }
  }
  if (failed > 0) return cli::ExitCode::kRuntimeError;
  return skipped > 0 ? cli::ExitCode::kInterrupted : cli::ExitCode::kOk;
}

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
      ->check(cli::PositiveNumber());
  sim->add_option("--plot", o->plot_path,
                  "Draw the paper-style figure (S_out and each phi_i against time) to this PNG");
  sim->add_flag("--json", o->json, "Print one JSON object with the results");
  sim->add_flag("--progress", o->progress, "Show a progress bar (default: on a terminal)");
  sim->add_flag("--no-progress", o->no_progress, "Never show a progress bar");
  sim->add_flag("--print-scenario", o->print_scenario,
                "Print the effective scenario (after overrides) in text format and exit");
  sim->add_option("--seeds", o->seeds,
                  "One run per seed (a list and ranges: 1-10, 1,2,5-7) on every core; prints each "
                  "run and the mean ± standard deviation (min – max) over the seeds")
      ->excludes(sim->get_option("--seed"))
      ->excludes(sim->get_option("--trace"))
      ->excludes(sim->get_option("--plot"))
      ->excludes(sim->get_option("--print-scenario"));
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
  std::vector<std::string> warnings = o.overrides.IgnoredFlags(simulator->scenario());
  for (std::string& w : ScenarioWarnings(simulator->scenario())) warnings.push_back(std::move(w));
  for (const auto& w : warnings) fmt::print(stderr, "dpc sim: warning: {}\n", w);
  if (!o.seeds.empty()) return RunSeeds(o, simulator->scenario(), warnings);

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
