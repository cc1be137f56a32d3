#pragma once
// `dpc replay FILE.mcap`: re-publishes a recording's messages (as `dpc record` stored them: the
// payloads as they arrived) on their topics with their original timing — scaled by --rate, or as
// fast as possible with --rate 0 — once or in a --loop, so tools and dashboards can be developed
// against a recording. Each message is checked with its type before it is published (one that
// does not decode is counted and skipped); its partition comes from its own bench id (and
// controller id, for commands). Refuses a domain where a bench runs (a writer of samples or
// states in any bench's partition): a replay beside a live bench would steer or confuse it.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "bus_tool_support.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct ReplayOptions {
  BusToolOptions bus;
  std::string input_path;
  double rate = 1.0;                ///< time scale: 2 = twice as fast; 0 = as fast as possible
  bool loop = false;                ///< start again at the end, until Ctrl-C
  std::vector<std::string> topics;  ///< empty: every bench topic of the recording
  double discovery_wait_s = 1.5;    ///< how long to look for a running bench before publishing
};

CLI::App* AddReplayCommand(CLI::App& app, ReplayOptions* options);
cli::ExitCode RunReplayCommand(const ReplayOptions& options);

}  // namespace dpc::tools
