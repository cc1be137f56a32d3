#include "sweep_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <atomic>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>
#include <map>

#include "dpc/cli/command_line.h"
#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/sim/loop_stability.h"
#include "dpc/sim/sweep_runner.h"
#include "dpc/cli/exit_code.h"
#include "dpc/cli/run_report.h"
#include "paper_figure.h"
#include "progress_bar.h"
#include "dpc/cli/scenario_loading.h"

namespace dpc::tools {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void OnSweepInterrupt(int) { g_stop.store(true); }

struct Cell {
  std::string device, method, prediction;
  double rate_rad_per_s;
  std::vector<const SimulationResult*> runs;
  int failed = 0;
  std::string error;
};

// The sweep flag behind a single-run flag that the grid sets.
std::string SweepFlagFor(const std::string& run_flag) {
  if (run_flag == "--method") return "--methods";
  if (run_flag == "--stages-axes") return "--devices";
  if (run_flag == "--rate-rad-per-s") return "--rates";
  if (run_flag == "--seed") return "--seeds";
  if (run_flag == "--predict" || run_flag == "--no-predict") return "--predictions";
  return run_flag;
}

double Mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? NAN : sum / static_cast<double>(v.size());
}

}  // namespace

CLI::App* AddSweepCommand(CLI::App& app, SweepOptions* o) {
  CLI::App* sweep = app.add_subcommand(
      "sweep", "Simulate a grid of rates x methods x seeds (x devices) on all cores");
  sweep->add_option("scenario", o->scenario_path, "Base scenario (default: the paper's)")
      ->check(CLI::ExistingFile);
  o->overrides.AddTo(*sweep);
  sweep->add_option("--rates", o->rates_rad_per_s, "Input rotation rates (rad/s), comma separated")
      ->delimiter(',')
      ->check(cli::NonNegativeNumber());
  sweep->add_option("--methods", o->methods, "Control laws, comma separated")->delimiter(',');
  sweep->add_option("--seeds", o->seeds, "Seeds: a list and ranges, e.g. 1-10 or 1,2,5-7 (default: the scenario's)");
  sweep->add_option("--devices", o->devices,
                    "Stage axes per device, comma separated (e.g. 131,3131)")
      ->delimiter(',');
  sweep->add_option("--predictions", o->predictions,
                    "Delay compensation per run, comma separated: off,on (default: as the "
                    "scenario and --predict say)")
      ->delimiter(',')
      ->check(CLI::IsMember({"off", "on"}));
  sweep->add_option("--reference-deg", o->reference_deg,
                    "Dashed reference lines on the plot at these errors (deg), e.g. 1.15 "
                    "(40 dB extinction)")
      ->delimiter(',');
  sweep->add_option("--jobs", o->jobs, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  sweep->add_flag("--json", o->json, "Print one JSON object per run (JSON lines)");
  sweep->add_option("--csv", o->csv_path, "Write the aggregated table as CSV");
  sweep->add_option("--plot", o->plot_path, "Draw mean error against rate (log-log) to this PNG");
  sweep->add_flag("--no-progress", o->no_progress, "No progress line");
  return sweep;
}

cli::ExitCode RunSweepCommand(const SweepOptions& o) {
  ScenarioConfig base;
  try {
    base = cli::LoadScenarioWithOverrides(o.scenario_path, o.overrides, PaperScenario("131"));
  } catch (const ScenarioError& e) {
    fmt::print(stderr, "dpc sweep: {}\n", cli::DescribeScenarioError(e, o.overrides));
    return cli::ExitCode::kInvalidInput;
  }
  std::vector<std::string> devices = o.devices;
  if (devices.empty()) devices.push_back("");
  std::vector<std::string> methods = o.methods;
  if (methods.empty()) methods.push_back(std::string(MethodName(base.controller.method)));
  std::vector<double> rates = o.rates_rad_per_s;
  if (rates.empty()) rates.push_back(cli::InputRateRadPerS(base));
  std::vector<uint64_t> seeds;
  try {
    if (!o.seeds.empty()) seeds = cli::ParseSeedList(o.seeds);
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "dpc sweep: --seeds: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }
  if (seeds.empty()) seeds.push_back(base.simulation.seed);
  std::vector<std::string> predictions = o.predictions;
  if (predictions.empty()) predictions.push_back("");

  // Build the grid; invalid combinations are reported before anything runs.
  std::vector<std::string> warnings;  // each distinct one once
  std::vector<ScenarioConfig> scenarios;
  std::vector<Cell> cells;
  std::vector<size_t> cell_of_run;
  for (const auto& device : devices) {
    for (const auto& method : methods) {
     for (const auto& prediction : predictions) {
      for (double rate : rates) {
        Cell cell{device, method, prediction, rate, {}, 0, {}};
        for (uint64_t seed : seeds) {
          cli::ScenarioOverrides grid;
          if (!device.empty()) grid.stages_axes = device;
          grid.method = method;
          grid.predict = prediction == "on";
          grid.no_predict = prediction == "off";
          if (std::isfinite(rate)) grid.rate_rad_per_s = rate;
          grid.seed = seed;
          ScenarioConfig scenario = base;
          try {
            grid.Apply(&scenario);
          } catch (const ScenarioError& e) {
            // The grid's values come from the sweep's list flags: name those.
            fmt::print(stderr, "dpc sweep: {}: {}\n", SweepFlagFor(e.location()), e.message());
            return cli::ExitCode::kInvalidInput;
          }
          try {
            ValidateScenario(scenario);
          } catch (const ScenarioError& e) {
            // A field the grid set is named by the run; the others by the flag that set them.
            const std::string text = grid.FlagForField(e.location())
                                         ? fmt::format("invalid scenario: {}", e.what())
                                         : cli::DescribeScenarioError(e, o.overrides);
            fmt::print(stderr,
                       "dpc sweep: {} (run: device {}, method {}, rate {:g} rad/s, seed {})\n",
                       text, device.empty() ? "scenario" : device, method, rate, seed);
            return cli::ExitCode::kInvalidInput;
          }
          std::vector<std::string> run_warnings = o.overrides.IgnoredFlags(scenario);
          for (std::string& w : ScenarioWarnings(scenario)) run_warnings.push_back(std::move(w));
          for (const std::string& warning : run_warnings) {
            if (std::find(warnings.begin(), warnings.end(), warning) == warnings.end()) {
              warnings.push_back(warning);
            }
          }
          scenarios.push_back(std::move(scenario));
          cell_of_run.push_back(cells.size());
        }
        cells.push_back(std::move(cell));
      }
     }
    }
  }

  for (const std::string& warning : warnings) fmt::print(stderr, "dpc sweep: warning: {}\n", warning);
  ProgressBar progress("dpc sweep", !o.no_progress && ProgressBar::StderrIsTerminal());
  g_stop.store(false);
  const auto previous_int = std::signal(SIGINT, OnSweepInterrupt);
  const auto sweep_start = std::chrono::steady_clock::now();
  const std::vector<SweepOutcome> outcomes =
      RunSweep(scenarios, o.jobs, [&](size_t done, size_t total) {
        progress.Update(static_cast<int64_t>(done), static_cast<int64_t>(total));
      }, &g_stop);
  std::signal(SIGINT, previous_int);
  progress.Finish();
  fmt::print(stderr, "dpc sweep: {}\n",
             cli::DescribeSweepSpeed(outcomes, o.jobs, std::chrono::duration<double>(
                                                           std::chrono::steady_clock::now() - sweep_start)
                                                           .count()));

  for (size_t i = 0; i < outcomes.size(); ++i) {
    Cell& cell = cells[cell_of_run[i]];
    if (outcomes[i].ok) {
      cell.runs.push_back(&outcomes[i].result);
    } else {
      ++cell.failed;
      cell.error = outcomes[i].error;
    }
    if (o.json && outcomes[i].ok) {
      // The settings come from a simulator built (cheaply) for the report.
      const ClosedLoopSimulator simulator(scenarios[i]);
      std::cout << cli::RunReportJson(cli::DescribeRun(simulator), outcomes[i].result, {}).dump() << '\n';
    }
  }

  // Table: mean over seeds of each run's statistics.
  std::string table = fmt::format("{:<8} {:<9} {:<4} {:>12} {:>5} {:>10} {:>10} {:>10} {:>8} {:>12} {:>10}\n",
                                  "device", "method", "pred", "rate_rad/s", "runs", "mean_deg",
                                  "p99_deg", "max_deg", "locked", "extinct_dB", "nullsp_%");
  std::string csv =
      "device,method,rate_rad_per_s,runs,error_deg_mean,error_deg_p99,error_deg_max,locked_runs,"
      "extinction_db_mean,nullspace_active_fraction,prediction\n";
  std::map<std::string, RateSeries> series;
  for (const Cell& cell : cells) {
    std::vector<double> mean, p99, extinction, nullspace;
    double max = NAN;
    int locked = 0;
    for (const SimulationResult* r : cell.runs) {
      mean.push_back(r->summary.error_deg.mean);
      p99.push_back(r->summary.error_deg.p99);
      extinction.push_back(r->summary.extinction_db_mean);
      nullspace.push_back(r->summary.nullspace_active_fraction);
      if (!(r->summary.error_deg.max <= max)) max = r->summary.error_deg.max;
      locked += r->summary.lock_time_s.has_value();
    }
    const std::string device = cell.device.empty() ? "scenario" : cell.device;
    const std::string prediction = cell.prediction.empty() ? "-" : cell.prediction;
    table += fmt::format("{:<8} {:<9} {:<4} {:>12.4g} {:>5} {:>10.4f} {:>10.4f} {:>10.4f} {:>5}/{:<2} {:>12.2f} {:>10.1f}",
                         device, cell.method, prediction, cell.rate_rad_per_s, cell.runs.size(),
                         Mean(mean), Mean(p99), max, locked, cell.runs.size(), Mean(extinction),
                         100.0 * Mean(nullspace));
    if (cell.failed) table += fmt::format("  ({} failed: {})", cell.failed, cell.error);
    table += '\n';
    csv += fmt::format("{},{},{:.9g},{},{:.9g},{:.9g},{:.9g},{},{:.9g},{:.9g},{}\n", device,
                       cell.method, cell.rate_rad_per_s, cell.runs.size(), Mean(mean), Mean(p99),
                       max, locked, Mean(extinction), Mean(nullspace), prediction);
    std::string label = device == "scenario" ? cell.method : device + " " + cell.method;
    if (cell.prediction == "on") label += " + prediction";
    if (cell.prediction == "off") label += ", no prediction";
    RateSeries& s = series[label];
    s.label = label;
    if (std::isfinite(Mean(mean))) {
      s.rate_rad_per_s.push_back(cell.rate_rad_per_s);
      s.error_deg.push_back(Mean(mean));
    }
  }
  if (!o.json) fmt::print("{}", table);
  try {
    if (!o.csv_path.empty()) {
      std::ofstream out(o.csv_path);
      out << csv;
      if (!out) throw std::runtime_error("cannot write " + o.csv_path);
    }
    if (!o.plot_path.empty()) {
      std::vector<RateSeries> plot_series;
      for (auto& [label, s] : series) plot_series.push_back(s);
      std::vector<RateReferenceLine> references;
      for (double error : o.reference_deg) {
        references.push_back({error, fmt::format("{:g}°", error)});
      }
      WriteRatePlot(o.plot_path, fmt::format("{}: mean error against input rotation rate",
                                             base.name),
                    plot_series, references);
      if (!o.json) fmt::print("plot {}\n", o.plot_path);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc sweep: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
  for (const Cell& cell : cells) {
    if (cell.failed) return g_stop.load() ? cli::ExitCode::kInterrupted : cli::ExitCode::kRuntimeError;
  }
  return cli::ExitCode::kOk;
}

}  // namespace dpc::tools
