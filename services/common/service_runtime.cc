#include "service_runtime.h"

#include <sched.h>

#include <cerrno>
#include <cstring>
#include <memory>

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include "dpc/bench/clock.h"
#include "dpc/cli/loop_guard.h"
#include "dpc/scenario_io/scenario_reader.h"
#include "dpc/cli/scenario_loading.h"

namespace dpc::services {

std::string IdentifierProblem(const std::string& id) {
  if (id.empty() || id.size() > 63) return "must have 1 to 63 characters";
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) return fmt::format("'{}' is not allowed (only A-Z a-z 0-9 _ -)", c);
  }
  return {};
}

void AddCommonOptions(CLI::App& app, CommonOptions* options) {
  app.add_option("SCENARIO", options->scenario_file,
                 "Scenario file (text format, common/proto/dpc/scenario.proto); default: the "
                 "embedded bench scenario (deploy/scenarios/bench_default.pbtxt)")
      ->check(CLI::ExistingFile);
  app.add_option("--domain", options->domain_id, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  app.add_option("--bench-id", options->bench_id,
                 "Bench id: the key of every topic, so that benches can share a domain")
      ->check([](const std::string& id) { return IdentifierProblem(id); })
      ->capture_default_str();
  app.add_option("--security-dir", options->security_dir,
                 "DDS Security: the bench's credentials (deploy/security/make-bench-pki.sh); the "
                 "participant authenticates, is access-controlled and encrypts. Empty: security off")
      ->envname("DPC_SECURITY_DIR")
      ->check(CLI::ExistingDirectory);
  app.add_option("--identity", options->identity,
                 "DDS Security: the identity in --security-dir (default: the service's role: "
                 "driver, polarimeter, controller-<id>)")
      ->envname("DPC_IDENTITY");
  app.add_option("--realtime-priority", options->realtime_priority,
                 "Run under SCHED_FIFO at this priority (1-99; 0: the default scheduling): the bench's "
                 "processes then run before any ordinary one; needs CAP_SYS_NICE or ulimit -r")
      ->envname("DPC_REALTIME_PRIORITY")
      ->check(CLI::Range(0, 99))
      ->capture_default_str();
  app.add_option("--stuck-exit-s", options->stuck_exit_s,
                 "Exit with code 1, saying where, when the service's loop has not turned for this long "
                 "(a call into Fast DDS or a device that never returns), so that a supervisor restarts "
                 "it; raised to what the service's own timeouts need. Also when the event thread of its DDS "
                 "participant has not run for 3 s (a Fast DDS deadlock). 0: never")
      ->envname("DPC_STUCK_EXIT_S")
      ->check(cli::StuckExitProblem)
      ->capture_default_str();
  app.add_option("--log-level", options->log_level, "trace|debug|info|warn|error|off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  options->overrides.AddTo(app);
}

ScenarioConfig LoadServiceScenario(const CommonOptions& options) {
  return LoadServiceScenario(options, DefaultBenchScenarioText(), "<bench_default.pbtxt>");
}

ScenarioConfig LoadServiceScenario(const CommonOptions& options, const char* default_text,
                                   const std::string& default_name) {
  return cli::LoadScenarioWithOverrides(
      options.scenario_file, options.overrides,
      options.scenario_file.empty() ? ScenarioFromProto(ParseScenarioText(default_text, default_name))
                                    : ScenarioConfig{});
}

std::string DescribeError(const ScenarioError& error, const CommonOptions& options) {
  return cli::DescribeScenarioError(error, options.overrides);
}

std::string ApplyRealtimePriority(int priority) {
  if (priority == 0) return {};
  sched_param parameters{};
  parameters.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &parameters) != 0) {
    const int error = errno;
    return fmt::format("--realtime-priority {}: SCHED_FIFO refused ({}); it needs CAP_SYS_NICE or an "
                       "RLIMIT_RTPRIO of at least {} (ulimit -r)",
                       priority, std::strerror(error), priority);
  }
  return {};
}

void SetUpLogging(const std::string& service, const CommonOptions& options) {
  spdlog::drop(service);  // set up again (a test runs several services in one process)
  auto logger = spdlog::stderr_logger_mt(service);
  logger->set_pattern(fmt::format("%H:%M:%S.%e [{} {}] %^%l%$: %v", service, options.bench_id));
  logger->set_level(spdlog::level::from_str(options.log_level));
  spdlog::set_default_logger(logger);
}

PeerLog::PeerLog(Now now) : now_(now ? std::move(now) : Now(MonotonicNs)) {}

void PeerLog::operator()(bool warning, const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now_ns = now_();
  if (!started_ || now_ns - window_start_ns_ >= kWindowNs) {
    started_ = true;
    window_start_ns_ = now_ns;
    lines_in_window_ = 0;
  }
  if (lines_in_window_ >= kLines) {
    ++not_shown_;
    return;
  }
  ++lines_in_window_;
  const std::string suffix = not_shown_ == 0 ? "" : fmt::format(" ({} peer events before it not shown)", not_shown_);
  not_shown_ = 0;
  spdlog::log(warning ? spdlog::level::warn : spdlog::level::info, "{}{}", text, suffix);
}

void LogLine(bool error, const std::string& text) {
  spdlog::log(error ? spdlog::level::err : spdlog::level::info, "{}", text);
}

std::function<void(bool, const std::string&)> PeerLogger() {
  return [log = std::make_shared<PeerLog>()](bool warning, const std::string& text) { (*log)(warning, text); };
}

void RejectionLog::Update(uint64_t count, const std::string& last_reason) {
  if (count == reported_) return;
  if (reported_ == 0 || count / kEvery != reported_ / kEvery) {
    spdlog::warn("{} #{}: {}", what_, count, last_reason);
  }
  reported_ = count;
}

}  // namespace dpc::services
