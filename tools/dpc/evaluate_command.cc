#include "evaluate_command.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "bus_tool_support.h"
#include "child_process.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/recorded_bench.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/scenario_loading.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/control/target.h"
#include "dpc/scenario_io/scenario_reader.h"
#include "dpc/scenario_io/scenario_writer.h"
#include "dpc/sim/run_statistics.h"

namespace dpc::tools {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

constexpr double kDegPerRad = 180.0 / M_PI;
/// A recording this short says nothing about a controller.
constexpr size_t kMinSamples = 100;
/// The lockstep polarimeter gives up when no state answers a sample for this long (a controller
/// that takes long to start, e.g. an interpreter, still joins).
constexpr double kLockstepTimeoutS = 30.0;

/// What the recording says about its session: what the evaluation repeats.
struct Session {
  bus::RecordedBench recording;
  std::vector<StageConfig> stages;
  TargetConfig target;
  uint64_t target_revision = 0;
  double rate_hz = 0.0;
  size_t samples = 0;            ///< the recording's samples evaluated (up to a target change)
  int64_t input_samples = 0;     ///< the evaluation's samples (missing ones filled)
  int64_t delay_samples = 1;     ///< the recorded loop delay (median), or --delay-samples
  int64_t recorded_delay_p50 = 0, recorded_delay_p99 = 0;
  std::vector<double> initial_phi;
  std::vector<std::string> notes;
};

std::string ServiceBinary(const std::string& name, const char* build_path) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && fs::is_regular_file(exe.parent_path() / name)) return (exe.parent_path() / name).string();
  if (fs::is_regular_file(build_path)) return build_path;
  return name;  // from PATH
}

int64_t Percentile(std::vector<int64_t> values, double q) {
  if (values.empty()) return 0;
  auto at = values.begin() + static_cast<std::ptrdiff_t>(std::min(values.size() - 1, static_cast<size_t>(q * values.size())));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

/// The base scenario: --scenario, else the recorded one (dpc record --scenario), else the
/// paper's. Only what the run does not take from the recording is used: the lock threshold,
/// the statistics window, the seed, the controller section (for `{scenario}`).
ScenarioConfig BaseScenario(const EvaluateOptions& o, const bus::RecordedBench& recording, std::string* from) {
  if (!o.scenario_path.empty()) {
    *from = o.scenario_path;
    return cli::LoadScenarioWithOverrides(o.scenario_path, {}, PaperScenario("131"));
  }
  if (const auto it = recording.metadata.find("scenario"); it != recording.metadata.end()) {
    if (const auto text = it->second.find("text"); text != it->second.end()) {
      *from = "the recording's scenario";
      return ScenarioFromProto(ParseScenarioText(text->second, o.input_path + " (metadata scenario)"));
    }
  }
  *from = "the paper's scenario (defaults)";
  return PaperScenario("131");
}

Session ReadSession(const EvaluateOptions& o, const ScenarioConfig& base) {
  Session s;
  bus::RecordedBenchOptions read;
  read.from_s = o.from_s;
  read.duration_s = o.duration_s;
  s.recording = bus::ReadRecordedBench(o.input_path, read);
  const bus::RecordedBench& r = s.recording;
  if (!r.complete) s.notes.push_back(fmt::format("the file is cut short ({}): evaluated up to there", r.problem));
  if (r.later_runs) s.notes.push_back("a restarted bench follows in the file: only the first run is evaluated");
  if (r.rejected > 0) {
    s.notes.push_back(fmt::format("{} messages failed their check and were left out (last: {})", r.rejected,
                                  r.last_rejection));
  }
  if (r.samples.size() < kMinSamples) {
    throw std::invalid_argument(fmt::format("{} holds {} usable samples{}; at least {} are needed", o.input_path,
                                            r.samples.size(), o.from_s > 0 ? " in the chosen window" : "", kMinSamples));
  }
  if (r.device) {
    s.stages = r.device->stages;
  } else if (!o.scenario_path.empty()) {
    s.stages = base.stages;
    s.notes.push_back("no device description recorded: the device of --scenario");
  } else {
    throw std::invalid_argument(fmt::format(
        "{} holds no device description (dpc_device_description): give the device with --scenario", o.input_path));
  }
  // The target in force at the first sample; a later change ends the evaluated window.
  const uint64_t first_ns = r.samples.front().log_time_ns;
  const bus::RecordedTarget* in_force = nullptr;
  const bus::RecordedTarget* change = nullptr;
  for (const bus::RecordedTarget& t : r.targets) {
    if (t.log_time_ns <= first_ns || in_force == nullptr) {
      in_force = &t;
    } else if (t.target.revision != in_force->target.revision) {
      change = &t;
      break;
    }
  }
  if (in_force != nullptr) {
    s.target = in_force->target.target;
    s.target_revision = in_force->target.revision;
  } else {
    s.target = base.target;
    s.notes.push_back("no target recorded: the target of the base scenario");
  }
  s.samples = r.samples.size();
  if (change != nullptr) {
    const auto cut = std::find_if(r.samples.begin(), r.samples.end(),
                                  [&](const bus::RecordedSample& x) { return x.log_time_ns >= change->log_time_ns; });
    s.samples = static_cast<size_t>(cut - r.samples.begin());
    s.notes.push_back(fmt::format("the target changed {:.3f} s into the window: evaluated up to there",
                                  static_cast<double>(change->log_time_ns - first_ns) / 1e9));
    if (s.samples < kMinSamples) {
      throw std::invalid_argument(fmt::format("{}: only {} samples before the target changed; at least {} are needed",
                                              o.input_path, s.samples, kMinSamples));
    }
  }
  s.input_samples = static_cast<int64_t>(r.samples[s.samples - 1].sequence - r.samples.front().sequence + 1);
  s.rate_hz = r.SampleRateHz();
  if (!(s.rate_hz > 0.0)) throw std::invalid_argument(fmt::format("{}: the samples carry no usable bench time", o.input_path));

  // The loop delay as the bench had it: for each sample, how many samples back the sample lay
  // that the state in force (the latest one received before it) answered.
  std::vector<int64_t> delays;
  size_t next_state = 0;
  const bus::RecordedState* latest = nullptr;
  const bus::RecordedState* latest_any = nullptr;
  for (size_t i = 0; i < s.samples; ++i) {
    const bus::RecordedSample& sample = r.samples[i];
    while (next_state < r.states.size() && r.states[next_state].log_time_ns <= sample.log_time_ns) {
      latest_any = &r.states[next_state];
      if (!latest_any->holding && latest_any->answers_sample > 0) latest = latest_any;
      ++next_state;
    }
    if (i == 0 && latest_any != nullptr) {
      s.initial_phi.assign(r.state_phi.begin() + static_cast<std::ptrdiff_t>(latest_any->phi_offset),
                           r.state_phi.begin() + static_cast<std::ptrdiff_t>(latest_any->phi_offset + r.controls));
    }
    if (latest != nullptr && latest->answers_sample < sample.sequence) {
      delays.push_back(static_cast<int64_t>(sample.sequence - latest->answers_sample));
    }
  }
  if (s.initial_phi.empty() && !r.states.empty()) {
    s.initial_phi.assign(r.state_phi.begin() + static_cast<std::ptrdiff_t>(r.states.front().phi_offset),
                         r.state_phi.begin() + static_cast<std::ptrdiff_t>(r.states.front().phi_offset + r.controls));
  }
  if (s.initial_phi.empty()) s.notes.push_back("no driver state recorded: φ starts at 0");
  s.recorded_delay_p50 = Percentile(delays, 0.5);
  s.recorded_delay_p99 = Percentile(delays, 0.99);
  if (o.delay_samples > 0) {
    s.delay_samples = o.delay_samples;
  } else if (!delays.empty()) {
    s.delay_samples = std::max<int64_t>(1, s.recorded_delay_p50);
  } else {
    s.delay_samples = 1;
    s.notes.push_back("no active driver state recorded: a loop delay of 1 sample (--delay-samples to choose)");
  }
  return s;
}

/// The recorded session's own statistics: its measured S_out against the target, φ the latest
/// recorded state's, by the rule of dpc sim (from settle_samples after the first lock).
RunSummary RecordedStatistics(const Session& s, const ScenarioConfig& scenario) {
  const bus::RecordedBench& r = s.recording;
  const Target target = BuildTarget(s.target);
  const int controls = std::max(r.controls, static_cast<int>(s.initial_phi.size()));
  RunStatistics statistics(target, controls, 0.0, scenario.simulation.lock_threshold_deg,
                           scenario.simulation.statistics_start_s,
                           (static_cast<double>(scenario.simulation.settle_samples) - 0.5) / s.rate_hz);
  std::vector<double> phi = s.initial_phi;
  phi.resize(static_cast<size_t>(controls), 0.0);
  size_t next_state = 0;
  const int64_t t0_ns = r.samples.front().time_ns;
  for (size_t i = 0; i < s.samples; ++i) {
    const bus::RecordedSample& sample = r.samples[i];
    while (next_state < r.states.size() && r.states[next_state].log_time_ns <= sample.log_time_ns) {
      const size_t offset = r.states[next_state].phi_offset;
      std::copy(r.state_phi.begin() + static_cast<std::ptrdiff_t>(offset),
                r.state_phi.begin() + static_cast<std::ptrdiff_t>(offset + static_cast<size_t>(r.controls)), phi.begin());
      ++next_state;
    }
    statistics.AddSample(static_cast<double>(sample.time_ns - t0_ns) / 1e9, sample.s_out, phi.data());
  }
  return statistics.Summarize(s.input_samples, 0);
}

/// The scenario the evaluation bench runs: the recorded device, target, rate, loop delay and
/// starting φ; the input is the recording's (given to the polarimeter separately).
ScenarioConfig EvaluationScenario(ScenarioConfig scenario, const Session& s) {
  scenario.name = "evaluate";
  scenario.description = "dpc evaluate of " + fs::path(s.recording.path).filename().string();
  scenario.stages = s.stages;
  scenario.target = s.target;
  scenario.input.disturbances.clear();
  scenario.input.initial_sop = s.recording.samples.front().s_in;
  scenario.simulation.sample_rate_hz = s.rate_hz;
  scenario.simulation.delay_s = static_cast<double>(s.delay_samples) / s.rate_hz;
  scenario.simulation.duration_s = static_cast<double>(s.input_samples) / s.rate_hz;
  scenario.simulation.polarimeter_noise_deg = 0.0;  // the recorded S_in is already a measurement
  scenario.controller.activation_s = 0.0;
  scenario.controller.initial_phi = s.initial_phi;
  // A dither reset lasts at least one sample: the base's may be set for a faster bench.
  if (double& reset_s = scenario.controller.dither.reset_duration_s; reset_s < 1.0 / s.rate_hz) {
    reset_s = 1.0 / s.rate_hz;
  }
  ValidateScenario(scenario);
  return scenario;
}

json SummaryJson(const RunSummary& r) {
  const auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  const auto optional = [&](const std::optional<double>& v) { return v ? number(*v) : json(nullptr); };
  return {{"samples", r.samples},
          {"error_deg", {{"mean", number(r.error_deg.mean)}, {"p50", number(r.error_deg.p50)},
                         {"p99", number(r.error_deg.p99)}, {"max", number(r.error_deg.max)}}},
          {"extinction_db_mean", number(r.extinction_db_mean)},
          {"extinction_db_power_mean", number(r.extinction_db_power_mean)},
          {"first_lock_time_s", optional(r.first_lock_time_s)},
          {"lock_time_s", optional(r.lock_time_s)},
          {"excursions", r.excursions},
          {"threshold_crossings", r.threshold_crossings},
          {"statistics_from_s", number(r.statistics_start_s)},
          {"statistics_to_s", number(r.statistics_end_s)},
          {"statistics_samples", r.statistics_samples}};
}

/// `command` with its placeholders filled; `--domain D --bench-id B` appended when it names
/// neither {domain} nor {bench_id}.
std::string ExpandCommand(std::string command, int domain, const std::string& bench_id, const std::string& scenario) {
  const bool placed = command.find("{domain}") != std::string::npos || command.find("{bench_id}") != std::string::npos;
  const auto replace = [&](const std::string& from, const std::string& to) {
    for (size_t at = command.find(from); at != std::string::npos; at = command.find(from, at + to.size())) {
      command.replace(at, from.size(), to);
    }
  };
  replace("{dpc-controller}", ServiceBinary("dpc-controller", DPC_BUILD_CONTROLLER_BINARY));
  replace("{domain}", std::to_string(domain));
  replace("{bench_id}", bench_id);
  replace("{scenario}", scenario);
  if (!placed) command += fmt::format(" --domain {} --bench-id {}", domain, bench_id);
  return command;
}

std::string Tail(const fs::path& path, size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string out;
  for (size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) out += "    " + all[i] + "\n";
  return out;
}

/// The last "lockstep: N of M samples" the polarimeter logged, as a fraction.
std::optional<double> Progress(const fs::path& log) {
  std::ifstream in(log);
  std::optional<double> fraction;
  for (std::string line; std::getline(in, line);) {
    const size_t at = line.rfind("lockstep: ");
    if (at == std::string::npos) continue;
    long long done = 0, total = 0;
    if (std::sscanf(line.c_str() + at, "lockstep: %lld of %lld samples", &done, &total) == 2 && total > 0) {
      fraction = static_cast<double>(done) / static_cast<double>(total);
    }
  }
  return fraction;
}

/// What the evaluated controller said of itself on dpc_controller_status (a controller that
/// publishes none leaves it empty): its law and, over the run, its updates, the smallest σ_min,
/// the mean null-space share and update time, the longest update.
class StatusCollector {
 public:
  void OnStatus(const ControllerStatusReport& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++statuses_;
    law_ = status.law;
    updates_ = std::max(updates_, status.updates);
    failed_ = std::max(failed_, status.failed_updates);
    if (status.sigma_min > 0.0) sigma_min_ = std::min(sigma_min_, status.sigma_min);
    if (status.updates > 0) {
      nullspace_sum_ += status.nullspace_active_fraction;
      compute_mean_sum_ += status.compute_time_mean_s;
      ++periods_;
    }
    compute_max_s_ = std::max(compute_max_s_, status.compute_time_max_s);
  }
  void OnRejected() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++rejected_;
  }
  json Json() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (statuses_ == 0) return json(nullptr);
    const auto mean = [&](double sum) { return periods_ > 0 ? json(sum / static_cast<double>(periods_)) : json(nullptr); };
    return {{"law", law_},
            {"statuses", statuses_},
            {"rejected_statuses", rejected_},
            {"updates", updates_},
            {"failed_updates", failed_},
            {"sigma_min_min", std::isfinite(sigma_min_) ? json(sigma_min_) : json(nullptr)},
            {"nullspace_active_fraction_mean", mean(nullspace_sum_)},
            {"compute_time_mean_s", mean(compute_mean_sum_)},
            {"compute_time_max_s", compute_max_s_}};
  }

 private:
  mutable std::mutex mutex_;
  uint64_t statuses_ = 0, rejected_ = 0, updates_ = 0, failed_ = 0, periods_ = 0;
  std::string law_;
  double sigma_min_ = INFINITY, nullspace_sum_ = 0.0, compute_mean_sum_ = 0.0, compute_max_s_ = 0.0;
};

struct Run {
  std::string name, command;
  bool ok = false;
  std::string failure;
  json report;                 ///< the polarimeter's (dpc sim's figures)
  json controller = nullptr;   ///< StatusCollector::Json
  double wall_time_s = 0.0;
};

/// One controller on a bench of its own: driver, controller, lockstep polarimeter.
Run RunController(const EvaluateOptions& o, const Session& s, const fs::path& dir, const std::string& scenario_file,
                  const std::string& name, const std::string& command, int domain) {
  Run run;
  run.name = name;
  run.command = command;
  const std::string bench_id = s.recording.bench_id.empty() ? "bench1" : s.recording.bench_id;
  // The services of the evaluation use the shipped loopback profile and no credentials,
  // whatever the caller's environment says.
  const std::vector<std::string> unset = {"FASTRTPS_DEFAULT_PROFILES_FILE", "DPC_SECURITY_DIR", "DPC_IDENTITY"};
  const std::vector<std::string> env = {fmt::format("DPC_DOMAIN={}", domain), "DPC_BENCH_ID=" + bench_id,
                                        "DPC_EVALUATE_SCENARIO=" + scenario_file};
  const auto log = [&](const std::string& who, const char* stream) { return (dir / (who + "." + stream)).string(); };
  const std::string domain_arg = "--domain=" + std::to_string(domain), bench_arg = "--bench-id=" + bench_id;
  // The controller's own account of the run, as an observer of the evaluation's bench.
  StatusCollector statuses;
  bus::BusParticipant participant(bus::BusOptions{domain, "dpc evaluate/" + name, {}});
  auto status_reader = participant.MakeReader<msg::ControllerStatus>(
      bench_id, [&](const msg::ControllerStatus& message, const eprosima::fastdds::dds::SampleInfo&) {
        ControllerStatusReport report;
        if (bus::ReadStatus(message, &report).empty()) {
          statuses.OnStatus(report);
        } else {
          statuses.OnRejected();
        }
      });
  const auto started = Clock::now();
  ChildProcess driver({ServiceBinary("dpc-driver", DPC_BUILD_DRIVER_BINARY), scenario_file, domain_arg, bench_arg,
                       "--device-record", "none"},
                      log("driver", "out"), log("driver", "log"), env, unset);
  const std::string expanded = ExpandCommand(command, domain, bench_id, scenario_file);
  ChildProcess controller({"/bin/sh", "-c", "exec " + expanded}, log("controller", "out"), log("controller", "log"), env,
                          unset);
  ChildProcess polarimeter({ServiceBinary("dpc-polarimeter", DPC_BUILD_POLARIMETER_BINARY), scenario_file, domain_arg,
                            bench_arg, "--lockstep", "--json", "--summary-hz", "0", "--input-recording", o.input_path,
                            "--input-from-s", fmt::format("{:.9g}", o.from_s), "--lockstep-timeout-s",
                            fmt::format("{:g}", kLockstepTimeoutS)},
                           log("polarimeter", "out"), log("polarimeter", "log"), env, unset);
  const bool on_terminal = isatty(STDERR_FILENO) == 1;
  auto next_status = Clock::now() + std::chrono::seconds(2);
  std::optional<int> polarimeter_status;
  for (;;) {
    polarimeter_status = polarimeter.Poll();
    if (polarimeter_status) break;
    const auto failed = [&](const char* who, ChildProcess& p, const std::string& path) {
      if (const auto status = p.Poll()) {
        run.failure = fmt::format("the {} ended ({}) before the run did; its log ends:\n{}", who,
                                  ChildProcess::DescribeStatus(*status), Tail(path, 8));
        return true;
      }
      return false;
    };
    if (failed("controller", controller, log("controller", "log")) || failed("driver", driver, log("driver", "log"))) {
      break;
    }
    if (StopSignals::requested()) {
      run.failure = "stopped by a signal";
      break;
    }
    const double elapsed_s = std::chrono::duration<double>(Clock::now() - started).count();
    if (elapsed_s > o.timeout_s) {
      run.failure = fmt::format("no result after {:g} s (--timeout-s)", o.timeout_s);
      break;
    }
    if (Clock::now() >= next_status) {
      next_status = Clock::now() + std::chrono::seconds(2);
      const auto fraction = Progress(log("polarimeter", "log"));
      const std::string line = fmt::format("dpc evaluate: {}: {:.0f} s, {}", name, elapsed_s,
                                           fraction ? fmt::format("{:.0f} % of the recording", 100 * *fraction)
                                                    : std::string("starting"));
      if (on_terminal) {
        fmt::print(stderr, "\r\x1b[K{}", line);
      } else {
        fmt::print(stderr, "{}\n", line);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (on_terminal) fmt::print(stderr, "\r\x1b[K");
  run.wall_time_s = std::chrono::duration<double>(Clock::now() - started).count();
  if (!polarimeter_status) polarimeter.Stop();
  controller.Stop();
  driver.Stop();
  status_reader.reset();
  run.controller = statuses.Json();
  if (!run.failure.empty()) return run;
  if (!WIFEXITED(*polarimeter_status) || WEXITSTATUS(*polarimeter_status) != 0) {
    run.failure = fmt::format("the polarimeter ended ({}); its log ends:\n{}", ChildProcess::DescribeStatus(*polarimeter_status),
                              Tail(log("polarimeter", "log"), 8));
    return run;
  }
  std::ifstream out(log("polarimeter", "out"));
  std::string last;
  for (std::string line; std::getline(out, line);) {
    if (!line.empty()) last = line;
  }
  run.report = json::parse(last, nullptr, false);
  if (run.report.is_discarded() || !run.report.is_object()) {
    run.failure = "the polarimeter printed no report";
    return run;
  }
  run.ok = true;
  return run;
}

std::string Cell(const json& value, const char* format) {
  if (value.is_null()) return "–";
  if (value.is_number_float()) return fmt::format(fmt::runtime(format), value.get<double>());
  if (value.is_number_integer()) return fmt::format("{}", value.get<int64_t>());
  return value.dump();
}

/// Milliseconds, or "never".
std::string Milliseconds(const json& seconds) {
  return seconds.is_null() ? "never" : fmt::format("{:.3g}", seconds.get<double>() * 1e3);
}

void PrintTable(const json& recorded, const std::vector<Run>& runs) {
  std::vector<std::string> heads{"recorded"};
  for (const Run& r : runs) heads.push_back(r.name);
  struct Row {
    std::string label;
    std::vector<std::string> cells;
  };
  std::vector<Row> rows;
  const auto add = [&](const std::string& label, const std::function<std::string(const json&)>& of_recorded,
                       const std::function<std::string(const json&)>& of_run) {
    Row row{label, {of_recorded(recorded)}};
    for (const Run& r : runs) row.cells.push_back(r.ok ? of_run(r.report) : "failed");
    rows.push_back(std::move(row));
  };
  // A row of the statistics both the recording and each run have.
  const auto both = [&](const std::string& label, const std::function<std::string(const json&)>& f) { add(label, f, f); };
  const auto error = [](const char* which) {
    return [which](const json& j) { return Cell(j["error_deg"][which], "{:.3f}"); };
  };
  both("error mean (°)", error("mean"));
  both("error p50 (°)", error("p50"));
  both("error p99 (°)", error("p99"));
  both("error max (°)", error("max"));
  both("extinction mean (dB)", [](const json& j) { return Cell(j["extinction_db_mean"], "{:.1f}"); });
  both("first lock (ms)", [](const json& j) { return Milliseconds(j["first_lock_time_s"]); });
  both("excursions", [](const json& j) { return Cell(j["excursions"], "{}"); });
  both("statistics samples", [](const json& j) { return Cell(j["statistics_samples"], "{}"); });
  // What each controller reported of itself (dpc_controller_status), if it publishes that.
  const auto of_controller = [&](const std::string& label, const std::function<std::string(const json&)>& f) {
    Row row{label, {"–"}};
    for (const Run& r : runs) row.cells.push_back(r.controller.is_object() ? f(r.controller) : "–");
    rows.push_back(std::move(row));
  };
  of_controller("law (its status)", [](const json& c) { return c["law"].get<std::string>(); });
  of_controller("updates", [](const json& c) { return Cell(c["updates"], "{}"); });
  of_controller("failed updates", [](const json& c) { return Cell(c["failed_updates"], "{}"); });
  of_controller("smallest σ_min", [](const json& c) { return Cell(c["sigma_min_min"], "{:.3g}"); });
  of_controller("null-space active", [](const json& c) { return Cell(c["nullspace_active_fraction_mean"], "{:.3f}"); });
  of_controller("update time mean (µs)", [](const json& c) {
    return c["compute_time_mean_s"].is_number() ? fmt::format("{:.2f}", c["compute_time_mean_s"].get<double>() * 1e6)
                                                : std::string("–");
  });
  of_controller("update time max (µs)",
                [](const json& c) { return fmt::format("{:.1f}", c["compute_time_max_s"].get<double>() * 1e6); });

  const auto none = [](const json&) { return std::string("–"); };
  add("mean error / recorded", none, [&](const json& j) {
    const json& mine = j["error_deg"]["mean"];
    const json& theirs = recorded["error_deg"]["mean"];
    if (!mine.is_number() || !theirs.is_number() || theirs.get<double>() <= 0) return std::string("–");
    return fmt::format("{:.3f}", mine.get<double>() / theirs.get<double>());
  });

  size_t label_width = 0;
  for (const Row& r : rows) label_width = std::max(label_width, r.label.size());
  std::vector<size_t> widths;
  for (size_t c = 0; c < heads.size(); ++c) {
    size_t w = heads[c].size();
    for (const Row& r : rows) w = std::max(w, r.cells[c].size());
    widths.push_back(w);
  }
  // Widths by bytes: the labels' ° and σ are two bytes each but one column.
  const auto pad = [](const std::string& text, size_t width, bool left) {
    size_t shown = 0;
    for (unsigned char c : text) shown += (c & 0xC0) != 0x80;
    const std::string fill(width > shown ? width - shown : 0, ' ');
    return left ? text + fill : fill + text;
  };
  fmt::print("{}  ", pad("", label_width, true));
  for (size_t c = 0; c < heads.size(); ++c) fmt::print("  {}", pad(heads[c], widths[c], false));
  fmt::print("\n");
  for (const Row& r : rows) {
    fmt::print("{}  ", pad(r.label, label_width, true));
    for (size_t c = 0; c < r.cells.size(); ++c) fmt::print("  {}", pad(r.cells[c], widths[c], false));
    fmt::print("\n");
  }
}

}  // namespace

CLI::App* AddEvaluateCommand(CLI::App& app, EvaluateOptions* o) {
  CLI::App* evaluate = app.add_subcommand(
      "evaluate",
      "Judge controllers offline on a recorded session (dpc record's .mcap): each closes the loop in lockstep "
      "through the recorded input SOPs and the recorded device, with the recorded loop delay");
  evaluate->add_option("file", o->input_path, "The recording (.mcap)")->required()->check(CLI::ExistingFile);
  evaluate
      ->add_option("--controller", o->controllers,
                   "A controller's command (repeat to compare). Placeholders: {dpc-controller} (the bench's "
                   "controller program), {domain}, {bench_id}, {scenario} (the evaluation's scenario file); without "
                   "{domain} or {bench_id}, --domain D --bench-id B are appended. Also in its environment: "
                   "DPC_DOMAIN, DPC_BENCH_ID, DPC_EVALUATE_SCENARIO")
      ->required()
      ->take_all();
  evaluate->add_option("--name", o->names, "A name for each controller, in order (default A, B, …)")->take_all();
  evaluate->add_option("--delay-samples", o->delay_samples,
                       "Loop delay in samples (default: the recorded session's median)")
      ->check(CLI::Range(int64_t{1}, kMaxDelaySamples));
  evaluate->add_option("--from-s", o->from_s, "Start this far into the recording (bench time)")
      ->check(cli::NonNegativeNumber());
  evaluate->add_option("--duration-s", o->duration_s, "Evaluate this much of it (0: to the end)")
      ->check(cli::NonNegativeNumber());
  evaluate->add_option("--scenario", o->scenario_path,
                       "Lock threshold and statistics window (and the device, if none was recorded); default: the "
                       "recording's scenario (dpc record --scenario), else the paper's defaults");
  evaluate->add_option("--domain", o->domain_id, "DDS domain of the first controller's bench (the next count up)")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  evaluate->add_option("--logs", o->logs_dir, "Keep each run's scenario and service logs in this directory");
  evaluate->add_option("--timeout-s", o->timeout_s, "Give up on a controller after this long")
      ->check(cli::NumberIn(1.0, 86400.0))
      ->capture_default_str();
  evaluate->add_flag("--json", o->json, "Print one JSON object: the recording's figures and each run's report");
  return evaluate;
}

cli::ExitCode RunEvaluateCommand(const EvaluateOptions& o) {
  if (!o.names.empty() && o.names.size() != o.controllers.size()) {
    fmt::print(stderr, "dpc evaluate: --name: {} names for {} controllers\n", o.names.size(), o.controllers.size());
    return cli::ExitCode::kInvalidInput;
  }
  if (o.domain_id + static_cast<int>(o.controllers.size()) - 1 > 232) {
    fmt::print(stderr, "dpc evaluate: --domain {}: {} controllers need domains up to {} (at most 232)\n", o.domain_id,
               o.controllers.size(), o.domain_id + static_cast<int>(o.controllers.size()) - 1);
    return cli::ExitCode::kInvalidInput;
  }
  std::vector<std::string> names = o.names;
  for (size_t i = names.size(); i < o.controllers.size(); ++i) {
    names.push_back(i < 26 ? std::string(1, static_cast<char>('A' + i)) : fmt::format("C{}", i + 1));
  }

  Session session;
  ScenarioConfig scenario;
  std::string base_from;
  try {
    // The recording first (its scenario may be the base), then the session read with the base.
    bus::RecordedBenchOptions metadata_only;
    metadata_only.samples_only = true;
    metadata_only.duration_s = 1e-9;
    const ScenarioConfig base = BaseScenario(o, bus::ReadRecordedBench(o.input_path, metadata_only), &base_from);
    session = ReadSession(o, base);
    scenario = EvaluationScenario(base, session);
  } catch (const ScenarioError& e) {
    fmt::print(stderr, "dpc evaluate: {}: {}\n", base_from.empty() ? o.input_path : base_from,
               cli::DescribeScenarioError(e, {}));
    return cli::ExitCode::kInvalidInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc evaluate: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }
  const RunSummary recorded = RecordedStatistics(session, scenario);

  // A directory for the runs' scenario and logs: --logs, else a temporary one removed at the end.
  fs::path dir;
  bool remove_dir = false;
  try {
    if (!o.logs_dir.empty()) {
      dir = o.logs_dir;
      fs::create_directories(dir);
    } else {
      std::string pattern = (fs::temp_directory_path() / "dpc_evaluate_XXXXXX").string();
      if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot create a temporary directory");
      dir = pattern;
      remove_dir = true;
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc evaluate: --logs {}: {}\n", o.logs_dir, e.what());
    return cli::ExitCode::kInvalidInput;
  }
  const std::string scenario_file = (dir / "scenario.pbtxt").string();
  std::ofstream(scenario_file) << ScenarioToText(scenario);

  const Target built_target = BuildTarget(session.target);
  fmt::print(stderr, "dpc evaluate: {}: bench {}, {} samples at {:.0f} Hz ({:.3f} s), loop delay {} sample{} "
                     "(recorded p50 {}, p99 {}), target {}; settings from {}\n",
             o.input_path, session.recording.bench_id, session.samples, session.rate_hz,
             static_cast<double>(session.input_samples) / session.rate_hz, session.delay_samples,
             session.delay_samples == 1 ? "" : "s", session.recorded_delay_p50, session.recorded_delay_p99,
             built_target.Describe(), base_from);
  for (const std::string& note : session.notes) fmt::print(stderr, "dpc evaluate: note: {}\n", note);

  StopSignals signals;
  std::vector<Run> runs;
  bool all_ok = true;
  for (size_t i = 0; i < o.controllers.size() && !StopSignals::requested(); ++i) {
    const fs::path run_dir = dir / names[i];
    fs::create_directories(run_dir);
    fmt::print(stderr, "dpc evaluate: {}: {}\n", names[i], o.controllers[i]);
    try {
      runs.push_back(RunController(o, session, run_dir, scenario_file, names[i], o.controllers[i],
                                   o.domain_id + static_cast<int>(i)));
    } catch (const std::exception& e) {
      Run failed;
      failed.name = names[i];
      failed.command = o.controllers[i];
      failed.failure = e.what();
      runs.push_back(std::move(failed));
    }
    if (!runs.back().ok) {
      all_ok = false;
      fmt::print(stderr, "dpc evaluate: {} failed: {}\n", names[i], runs.back().failure);
    } else {
      fmt::print(stderr, "dpc evaluate: {} done in {:.1f} s\n", names[i], runs.back().wall_time_s);
    }
  }

  const json recorded_json = SummaryJson(recorded);
  if (o.json) {
    json out;
    out["recording"] = {{"path", o.input_path},
                        {"bench_id", session.recording.bench_id},
                        {"samples", session.samples},
                        {"samples_missing", session.recording.samples_missing},
                        {"sample_rate_hz", session.rate_hz},
                        {"duration_s", static_cast<double>(session.input_samples) / session.rate_hz},
                        {"loop_delay_samples", session.delay_samples},
                        {"recorded_delay_samples_p50", session.recorded_delay_p50},
                        {"recorded_delay_samples_p99", session.recorded_delay_p99},
                        {"target", built_target.Describe()},
                        {"target_revision", std::to_string(session.target_revision)},
                        {"initial_phi", session.initial_phi},
                        {"settings_from", base_from},
                        {"notes", session.notes},
                        {"statistics", recorded_json}};
    json list = json::array();
    for (const Run& r : runs) {
      json entry = {{"name", r.name},         {"command", r.command},       {"ok", r.ok},
                    {"wall_time_s", r.wall_time_s}, {"controller", r.controller}};
      if (r.ok) {
        entry["report"] = r.report;
      } else {
        entry["failure"] = r.failure;
      }
      list.push_back(std::move(entry));
    }
    out["runs"] = std::move(list);
    fmt::print("{}\n", out.dump());
  } else {
    PrintTable(recorded_json, runs);
  }
  if (remove_dir) {
    std::error_code ec;
    fs::remove_all(dir, ec);
  } else {
    fmt::print(stderr, "dpc evaluate: scenario and logs in {}\n", dir.string());
  }
  if (StopSignals::requested()) return cli::ExitCode::kOk;
  return all_ok ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
}

}  // namespace dpc::tools
