#pragma once
// `dpc info FILE.mcap [--json]`: what a recording holds, like `mcap info`: the file, its library,
// whether it ended properly (else what the reader recovered and where it stopped), duration,
// messages and chunks, metadata names, and per channel its topic, schema, message count, rate,
// and largest gap between two messages.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "dpc/cli/exit_code.h"
#include "dpc/record/mcap.h"

namespace dpc::tools {

struct InfoOptions {
  std::string path;
  bool json = false;
};

/// One channel's figures, from its messages' log times.
struct ChannelInfo {
  std::string topic, schema, encoding;
  uint64_t messages = 0;
  uint64_t first_ns = 0, last_ns = 0;
  uint64_t largest_gap_ns = 0;
  uint64_t largest_gap_at_ns = 0;  ///< log time of the message after it
};

/// Everything `dpc info` says about a file, read with ReadMcap.
struct RecordingInfo {
  uint64_t bytes = 0;
  record::McapReadResult read;
  std::map<uint16_t, ChannelInfo> channels;
  uint64_t first_ns = 0, last_ns = 0;
};

/// Throws std::runtime_error if the file cannot be read or is not MCAP.
RecordingInfo InspectRecording(const std::string& path);
std::string RecordingInfoText(const std::string& path, const RecordingInfo& info);

CLI::App* AddInfoCommand(CLI::App& app, InfoOptions* options);
cli::ExitCode RunInfoCommand(const InfoOptions& options);

}  // namespace dpc::tools
