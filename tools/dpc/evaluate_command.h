#pragma once
// `dpc evaluate FILE.mcap --controller "COMMAND" [--controller "COMMAND" …]`: a controller
// judged offline on a recorded bench session, before it is swapped into the live bench.
//
// For each controller, on a private loopback domain, a bench of real processes runs in lockstep:
// dpc-polarimeter takes the recording's input SOPs (its samples' S_in, --input-recording) and
// closes the loop through the simulated chain of the recorded device, dpc-driver validates and
// applies the commands as on the bench, and the controller is the command given (any program
// that speaks the bench's topics). The loop delay is the one the recorded session had (the
// median, in samples, from sample to the state that acted on the next ones), φ starts where the
// recorded waveplates were, the target is the recorded one. The report is `dpc sim`'s, side by
// side for every controller and beside the statistics of the recorded session itself (its
// measured S_out against the same target, the same statistics window rule).

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct EvaluateOptions {
  std::string input_path;
  std::vector<std::string> controllers;  ///< shell commands; placeholders below
  std::vector<std::string> names;        ///< one per controller; default A, B, …
  int64_t delay_samples = 0;             ///< 0: the recorded session's
  double from_s = 0.0;                   ///< bench time into the recording
  double duration_s = 0.0;               ///< 0: to its end (or the first target change)
  std::string scenario_path;             ///< lock threshold, settling, … (default: the recording's)
  int domain_id = 210;                   ///< the first controller's; the next ones count up
  std::string logs_dir;                  ///< keep each run's scenario and logs here
  double timeout_s = 600.0;              ///< per controller
  bool json = false;
};

CLI::App* AddEvaluateCommand(CLI::App& app, EvaluateOptions* options);
cli::ExitCode RunEvaluateCommand(const EvaluateOptions& options);

}  // namespace dpc::tools
