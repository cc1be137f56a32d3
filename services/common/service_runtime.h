#pragma once
// What every bench service shares besides its skeleton (service.h): the common command-line
// options (--domain, --bench-id, the scenario file and the `dpc sim` override flags), the
// scenario (a file or the embedded default), logging, and rate-limited reports of rejected
// input.

#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/cli/exit_code.h"
#include "dpc/cli/scenario_overrides.h"

namespace dpc::services {

struct CommonOptions {
  int domain_id = 0;
  std::string bench_id = "bench1";
  std::string scenario_file;   ///< empty: the embedded default (deploy/scenarios/bench_default.pbtxt)
  std::string log_level = "info";
  cli::ScenarioOverrides overrides;   ///< the `dpc sim` flags (--method, --step, --rate-rad-per-s, …)
  std::string security_dir;    ///< DDS Security credentials (make-bench-pki.sh); empty: off
  std::string identity;        ///< the identity in it; empty: the service's own role
};

/// "" if `id` may name a bench or a controller (1–63 of A–Z a–z 0–9 _ -: it becomes part of a
/// DDS partition and a certificate's name, so no wildcards or dots); else why not.
std::string IdentifierProblem(const std::string& id);

/// Adds --domain, --bench-id, the positional SCENARIO, --log-level, --security-dir and
/// --identity (also from $DPC_SECURITY_DIR, $DPC_IDENTITY) and the scenario override flags of
/// `dpc sim`.
void AddCommonOptions(CLI::App& app, CommonOptions* options);

/// The text of deploy/scenarios/bench_default.pbtxt, compiled in.
const char* DefaultBenchScenarioText();

/// The scenario file's contents, or the embedded default, with the override flags applied;
/// unvalidated (each service validates the parts it uses). Throws ScenarioError.
ScenarioConfig LoadServiceScenario(const CommonOptions& options);

/// "invalid scenario: controller.step: … (set by --step)".
std::string DescribeError(const ScenarioError& error, const CommonOptions& options);

/// Sets up spdlog ("[driver bench1] …" on stderr) at options.log_level (one of the names
/// --log-level accepts; the option checks it). Calling it again replaces the logger.
void SetUpLogging(const std::string& service, const CommonOptions& options);

/// Logs rejected input without letting a flood of it stall the loop: the first rejection, then
/// one line per kEvery more, each with the running count and the latest reason.
class RejectionLog {
 public:
  static constexpr uint64_t kEvery = 1000;
  explicit RejectionLog(std::string what) : what_(std::move(what)) {}
  /// Call after anything that may have rejected input, with the total so far.
  void Update(uint64_t count, const std::string& last_reason);

 private:
  std::string what_;
  uint64_t reported_ = 0;
};

}  // namespace dpc::services
