#pragma once
// `dpc topic list|echo|hz`: the bench's DDS topics from the command line.
//
//   dpc topic list [--domain N] [--wait-s 1.5]
//       every topic discovered on the domain: name, type, writer and reader counts; then the
//       participants. Exit 0 (also when nothing was found: a note on stderr).
//   dpc topic echo TOPIC [--domain N] [--bench-id ID] [--json] [--count N] [--timeout-s T]
//       every sample of one of the bench's topics (full name or alias: "dpc_waveplate_state",
//       "waveplate_state", "state"), one line each: readable text, or with --json one JSON
//       object with every field of the IDL type. --bench-id "" or "*" shows all benches.
//       Exit 0 after N samples (or on SIGINT/SIGTERM, or at the timeout if something arrived),
//       3 at the timeout with nothing received, 2 for an unknown topic (the valid ones listed).
//   dpc topic hz TOPIC [--window-s 1] [--count-windows N] [--timeout-s 5] [--json]
//       per window: the arrival rate (rate_hz) and the min/mean/max inter-arrival time (ms).
//       Windows start at the first sample; exit 3 if none arrives within --timeout-s.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "dpc/cli/exit_code.h"
#include "bus_tool_support.h"

namespace dpc::tools {

struct TopicListOptions {
  BusToolOptions bus;
  double wait_s = 1.5;
};

struct TopicEchoOptions {
  BusToolOptions bus;
  std::string topic;
  bool json = false;
  int64_t count = 0;       ///< 0: until stopped
  double timeout_s = 0.0;  ///< 0: none
};

struct TopicHzOptions {
  BusToolOptions bus;
  std::string topic;
  double window_s = 1.0;
  int64_t count_windows = 0;  ///< 0: until stopped
  double timeout_s = 5.0;     ///< for the first sample
  bool json = false;
};

struct TopicOptions {
  TopicListOptions list;
  TopicEchoOptions echo;
  TopicHzOptions hz;
  // The subcommands, to know which one was given (set by AddTopicCommand).
  CLI::App* list_command = nullptr;
  CLI::App* echo_command = nullptr;
  CLI::App* hz_command = nullptr;
};

/// Adds `topic` with its subcommands list, echo and hz.
CLI::App* AddTopicCommand(CLI::App& app, TopicOptions* options);

/// Runs the subcommand that was parsed; returns the process exit code.
cli::ExitCode RunTopicCommand(const TopicOptions& options);

cli::ExitCode RunTopicList(const TopicListOptions& options);
cli::ExitCode RunTopicEcho(const TopicEchoOptions& options);
cli::ExitCode RunTopicHz(const TopicHzOptions& options);

}  // namespace dpc::tools
