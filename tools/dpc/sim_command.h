#pragma once
// `dpc sim [SCENARIO.pbtxt] [flags]`: runs one closed-loop simulation and prints its summary
// (text, or one JSON object with --json), optionally streaming a trace and drawing the
// paper-style figure.

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "dpc/cli/exit_code.h"
#include "dpc/cli/scenario_overrides.h"

namespace dpc::tools {

struct SimOptions {
  std::string scenario_path;
  cli::ScenarioOverrides overrides;
  std::string trace_path;
  int64_t trace_every = 0;  ///< 0: automatic (at most ~50k rows)
  std::string plot_path;
  bool json = false;
  bool progress = false;
  bool no_progress = false;
  bool print_scenario = false;
  std::string seeds;  ///< "1-10", "1,2,5-7": one run per seed, reported with the spread over them
};

/// Adds the `sim` subcommand to `app`, storing its options in `options`.
CLI::App* AddSimCommand(CLI::App& app, SimOptions* options);

/// Runs it; returns the process exit code.
cli::ExitCode RunSimCommand(const SimOptions& options);

}  // namespace dpc::tools
