#pragma once
// `dpc target`: asks the bench's driver to change the target, and waits for its answer.
//
//   dpc target --point S1 S2 S3 [--domain N] [--bench-id ID] [--timeout-s 5]
//   dpc target --set-normal N1 N2 N3 [--offset C]     the set n·S = C
//   dpc target --linear                                any linear SOP: normal [0, 0, 1], offset 0
//
// The target is checked locally first (finite; a unit point to within 1e-6, not normalized;
// |offset|/|normal| < 1): a bad one is refused naming the flag, exit 2, and nothing is sent.
// Then a msg::TargetRequest with a fresh request_id goes to dpc_target_request once the
// driver's request reader has matched, and the driver's msg::TargetReply with that request_id
// is awaited on dpc_target_reply (a dpc_target sample naming the request also counts as
// accepted, in case the volatile reply was lost).
//
// Exit codes: 0 accepted (prints the new revision); 2 invalid input or refused by the driver
// (prints its message); 1 no driver matched or no reply within --timeout-s, or a DDS error.

#include <CLI/CLI.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "dpc/cli/exit_code.h"
#include "bus_tool_support.h"
#include "dpc/config/scenario_config.h"

namespace dpc::tools {

struct TargetOptions {
  BusToolOptions bus;
  std::vector<double> point;
  std::vector<double> normal;
  double offset = 0.0;
  bool linear = false;
  double timeout_s = 5.0;
};

CLI::App* AddTargetCommand(CLI::App& app, TargetOptions* options);

/// The linear-polarization target (the sphere's equator, n = S3, c = 0): `dpc target --linear`
/// and the dashboard's "linear".
TargetConfig LinearTarget();

/// `target` validated (ValidateTargetConfig). On a problem returns nullopt with `error` =
/// "<field>: <message>", the field named by `field_of(location)` (location as ScenarioError
/// gives it: "target.point.s1", "target.set.normal", …).
std::optional<TargetConfig> CheckedTarget(TargetConfig target,
                                          const std::function<std::string(const std::string&)>& field_of,
                                          std::string* error);

/// The target the flags describe, validated (ValidateTargetConfig). On a problem returns
/// nullopt with `error` naming the flag ("--point: [1, 1, 0] has |S| = 1.41421356; …").
std::optional<TargetConfig> TargetFromOptions(const TargetOptions& options, std::string* error);

cli::ExitCode RunTargetCommand(const TargetOptions& options);

}  // namespace dpc::tools
