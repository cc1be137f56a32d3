#pragma once
// `dpc dashboard`: the bench's live view in a web browser.
//
//   dpc dashboard [--port 8080] [--bind 127.0.0.1] [--domain N] [--bench-id ID]
//                 [--push-hz 20] [--lock-threshold-deg 10] [--assets DIR] [--duration-s T]
//
// Subscribes to the low-rate topics of one bench (the polarimeter's summaries, 20 a second, the
// controllers' status, the target, the device; never the samples or the states) and serves a page
// (tools/dpc/dashboard/web, with three.js and uPlot copied from npm at build time: nothing is
// fetched at run time) that shows the Poincaré sphere with S_in, S_out and the target, the error
// and extinction against time with the lock threshold and a LOCKED / LOST / HOLDING badge, φ per
// stage inside its range and against time, the driver's mode and reason, the obeyed controller,
// every controller's status, the sample rate and loop-latency percentiles. The page can set the
// target: its request takes the path of `dpc target` (a TargetRequest the driver validates) and
// the driver's answer is shown.
//
// The server pushes one JSON snapshot --push-hz times a second over a WebSocket (/ws): the page
// never receives the bench's rate. It keeps serving when the bench stops and shows it again when
// it comes back. It prints its URL on stdout ("dpc dashboard: http://127.0.0.1:8080/"), listens
// on 127.0.0.1 unless --bind says otherwise, and runs until SIGINT/SIGTERM or --duration-s.
//
// Requests from a page are untrusted input: at most 4 KiB, checked like `dpc target`'s flags,
// one outstanding per page and at most 4 a second in all; a refused one is answered with why.

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "bus_tool_support.h"
#include "dpc/cli/exit_code.h"
#include "dpc/config/scenario_config.h"

namespace dpc::tools {

struct DashboardOptions {
  BusToolOptions bus;
  int port = 8080;
  std::string bind_address = "127.0.0.1";
  double push_hz = 20.0;
  double lock_threshold_deg = 10.0;
  std::string assets_dir;  ///< empty: DefaultDashboardAssets()
  double duration_s = 0.0;
  double stuck_exit_s = 10.0;  ///< the loop guard's turn limit (cli::LoopGuard); 0: off
};

CLI::App* AddDashboardCommand(CLI::App& app, DashboardOptions* options);

cli::ExitCode RunDashboardCommand(const DashboardOptions& options);

/// Where the page's files are: $DPC_DASHBOARD_ASSETS, else <dir of dpc>/../share/dpc/dashboard
/// (installed), else the build tree's copy. Empty if none has an index.html.
std::string DefaultDashboardAssets();

/// A page's request to set the target: {"type": "set_target", "tag": "…", "kind": "point",
/// "point": [S1, S2, S3]} | {"kind": "set", "normal": [N1, N2, N3], "offset": C} |
/// {"kind": "linear"}. The target, validated (ValidateTargetConfig), or nullopt with `error`
/// saying what is wrong. `tag` (≤ 64 printable characters, echoed in the answer) is filled
/// whenever the message has one.
std::optional<TargetConfig> ParsePageTargetRequest(const std::string& text, std::string* tag, std::string* error);

}  // namespace dpc::tools
