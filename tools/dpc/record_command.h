#pragma once
// `dpc record -o FILE.mcap`: every topic of a bench (or the chosen ones) into an MCAP file, each
// message stored as the payload that arrived (CDR with its encapsulation: no re-encoding), its
// schema the IDL text of its type (encoding omgidl), log time = arrival, publish time = the
// writer's source timestamp. Metadata: the recorder (version, host, domain, bench), the scenario
// (--scenario), each device description the driver published, and the recording's own account
// (samples, sequence numbers missing, messages dropped). SIGINT/SIGTERM or --duration-s close the
// file properly; a kill -9 loses at most the last --flush-interval-s (the chunk being filled).

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "bus_tool_support.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct RecordOptions {
  BusToolOptions bus;
  std::string output_path;
  std::vector<std::string> topics;  ///< empty: every bench topic
  double duration_s = 0.0;          ///< 0: until SIGINT/SIGTERM
  std::string compression = "zstd";
  std::string scenario_path;        ///< kept as metadata "scenario" (validated first)
  double flush_interval_s = 1.0;    ///< the chunk being filled is written at least this often
  double stuck_exit_s = 10.0;       ///< the loop guard's turn limit (cli::LoopGuard); 0: off
  /// The UDP receive buffer asked for (bus::BusOptions::udp_receive_buffer_bytes), in MiB; 0:
  /// the profile's. What arrives while the recorder is not scheduled waits there.
  int udp_receive_buffer_mib = 4;
};

CLI::App* AddRecordCommand(CLI::App& app, RecordOptions* options);
cli::ExitCode RunRecordCommand(const RecordOptions& options);

}  // namespace dpc::tools
