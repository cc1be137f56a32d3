#pragma once
// `dpc sweep [SCENARIO] --rates … --methods … --seeds … [--devices 131,3131]
// [--predictions off,on]`: simulates every combination on all cores and prints the error
// against the input rotation rate as a table (mean over seeds), optionally as CSV, JSON lines
// and a log-log PNG plot (with --reference-deg lines, e.g. 1.15 for 40 dB extinction).

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "dpc/cli/exit_code.h"
#include "dpc/cli/scenario_overrides.h"

namespace dpc::tools {

struct SweepOptions {
  std::string scenario_path;
  cli::ScenarioOverrides overrides;
  std::vector<double> rates_rad_per_s;
  std::vector<std::string> methods;
  std::string seeds;  ///< "1-10", "1,2,5-7" (cli::ParseSeedList); empty: the scenario's seed
  std::vector<std::string> devices;
  std::vector<std::string> predictions;  ///< "off", "on"; empty: as the scenario and flags say
  std::vector<double> reference_deg;
  int jobs = 0;
  bool json = false;
  std::string csv_path;
  std::string plot_path;
  bool no_progress = false;
};

CLI::App* AddSweepCommand(CLI::App& app, SweepOptions* options);
cli::ExitCode RunSweepCommand(const SweepOptions& options);

}  // namespace dpc::tools
