// The bench as real processes on loopback: dpc-polarimeter, dpc-controller and dpc-driver talk
// over Fast DDS; the test watches the bus through its own participant and waits on conditions.
// Every test uses its own DDS domain (40–59) and ends every process it started.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "dpc/bus/bus_participant.h"
#include "dpc/bench/clock.h"
#include "support/child_process.h"
#include "support/json_lines.h"

namespace dpc {
namespace {

using dpc::testing::ChildProcess;
using dpc::testing::WaitUntil;
using dpc::testing::LastJsonLine;
using namespace std::chrono_literals;

std::string TempDir() {
  const std::string dir = ::testing::TempDir() + "dpc_bench_process_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  return dir;
}

/// One applied state as seen by the test.
struct SeenState {
  msg::WaveplateState state;
  int64_t seen_ns;
};

class BenchProcessTest : public ::testing::Test {
 protected:
  void StartObserver(int domain) {
    domain_ = domain;
    participant_ = std::make_unique<bus::BusParticipant>(bus::BusOptions{domain, "dpc-test-observer"});
    states_ = participant_->MakeReader<msg::WaveplateState>(
        "bench1", [this](const msg::WaveplateState& state, const auto&) {
          std::lock_guard<std::mutex> lock(mutex_);
          seen_.push_back({state, MonotonicNs()});
        });
    samples_ = participant_->MakeReader<msg::StokesSample>(
        "bench1", [this](const msg::StokesSample& sample, const auto&) {
          // Error of the measured output to the default target [0, 0.6, 0.8], degrees.
          const auto& s = sample.s_out();
          const double cosine = std::clamp(0.6 * s[1] + 0.8 * s[2], -1.0, 1.0);
          std::lock_guard<std::mutex> lock(mutex_);
          sample_errors_.push_back({sample.publish_time_ns(), std::acos(cosine) * 180.0 / M_PI});
        });
    statuses_ = participant_->MakeReader<msg::ControllerStatus>(
        "bench1", [this](const msg::ControllerStatus& status, const auto&) {
          std::lock_guard<std::mutex> lock(mutex_);
          statuses_seen_[status.controller_id().to_string()] = status;
        });
  }
  void TearDown() override {
    processes_.clear();  // ends them (SIGINT, then SIGKILL)
    statuses_.reset();
    samples_.reset();
    states_.reset();
    participant_.reset();
  }

  ChildProcess& Start(const std::string& binary, std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), binary);
    args.push_back("--domain");
    args.push_back(std::to_string(domain_));
    processes_.push_back(std::make_unique<ChildProcess>(args, dir_ + "/" + name + ".log"));
    return *processes_.back();
  }
  ChildProcess& StartDriver(std::vector<std::string> args = {}) {
    return Start(DPC_DRIVER_BINARY, std::move(args), "driver");
  }
  ChildProcess& StartController(const std::string& id, int priority, std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--id", id, "--priority", std::to_string(priority)});
    return Start(DPC_CONTROLLER_BINARY, std::move(args), "controller_" + id);
  }
  ChildProcess& StartPolarimeter(std::vector<std::string> args, const std::string& name = "polarimeter") {
    return Start(DPC_POLARIMETER_BINARY, std::move(args), name);
  }

  std::vector<SeenState> States() {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_;
  }
  size_t StateCount() {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_.size();
  }
  std::optional<msg::WaveplateState> LatestState() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (seen_.empty()) return std::nullopt;
    return seen_.back().state;
  }
  std::optional<msg::ControllerStatus> Status(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = statuses_seen_.find(id);
    if (it == statuses_seen_.end()) return std::nullopt;
    return it->second;
  }
  bool Obeys(const std::string& id) {
    auto state = LatestState();
    return state && state->mode() == msg::DRIVER_ACTIVE && state->obeyed_controller_id().to_string() == id;
  }
  /// Obeys(id) within `timeout`: the latest state may be a holding heartbeat of a stall of the
  /// whole machine, after which the driver gives control back to the same controller.
  bool SoonObeys(const std::string& id, std::chrono::milliseconds timeout = std::chrono::seconds(2)) {
    return WaitUntil([&] { return Obeys(id); }, timeout);
  }
  /// The largest output error of the samples published in [from_ns, to_ns] (wall clock).
  double MaxErrorDeg(int64_t from_ns, int64_t to_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    double worst = 0.0;
    for (const auto& [t, e] : sample_errors_) {
      if (t >= from_ns && t <= to_ns) worst = std::max(worst, e);
    }
    return worst;
  }
  /// Applied states obeying `id` seen so far.
  size_t AppliedBy(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t n = 0;
    for (const auto& s : seen_) n += s.state.obeyed_controller_id().to_string() == id && s.state.answers_sample() > 0;
    return n;
  }

  std::string Logs() {
    std::string all;
    for (auto& p : processes_) all += "---- " + p->log_path() + "\n" + p->Log();
    return all;
  }

  std::string dir_ = TempDir();
  int domain_ = 0;
  std::unique_ptr<bus::BusParticipant> participant_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> states_;
  std::unique_ptr<bus::Reader<msg::ControllerStatus>> statuses_;
  std::unique_ptr<bus::Reader<msg::StokesSample>> samples_;
  std::vector<std::pair<int64_t, double>> sample_errors_;  ///< (publish time ns, error deg)
  std::mutex mutex_;
  std::vector<SeenState> seen_;
  std::map<std::string, msg::ControllerStatus> statuses_seen_;
  std::vector<std::unique_ptr<ChildProcess>> processes_;
};

double MaxAbsDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}


TEST_F(BenchProcessTest, ThreeServicesLockOnLoopback) {
  StartObserver(40);
  StartDriver();
  StartController("A", 0);
  ChildProcess& polarimeter = StartPolarimeter({"--rate-hz", "2000", "--run-s", "4", "--json"});
  ASSERT_EQ(polarimeter.Wait(30s), 0) << Logs();
  const nlohmann::json report = LastJsonLine(polarimeter.Log());
  ASSERT_TRUE(report.is_object()) << Logs();
  ASSERT_FALSE(report["lock_time_s"].is_null()) << report.dump(2);
  // Loose: this checks the loop works across processes; bench/ measures how well.
  EXPECT_LT(report["error_deg"]["mean"].get<double>(), 5.0) << report.dump(2);
  EXPECT_EQ(report["bench"]["rejected_states"].get<int>(), 0);
  // The bench's own view of the loop latency: every answered sample, spans in order.
  const nlohmann::json& latency = report["bench"]["loop_latency_us"];
  const nlohmann::json& loop = latency["sample_to_state_received"];
  EXPECT_GT(loop["count"].get<int64_t>(), 4000) << latency.dump(2);
  EXPECT_GT(latency["sample_to_command_at_driver"]["p50"].get<double>(), 0.0) << latency.dump(2);
  EXPECT_LE(latency["sample_to_command_at_driver"]["p50"].get<double>(),
            latency["sample_to_state_published"]["p50"].get<double>());
  EXPECT_LE(latency["sample_to_state_published"]["p50"].get<double>(), loop["p50"].get<double>());
  EXPECT_LE(loop["p50"].get<double>(), loop["p99"].get<double>());
  EXPECT_EQ(latency["implausible"].get<int>(), 0);
  EXPECT_GT(AppliedBy("A"), 4000u);
  const auto status = Status("A");
  ASSERT_TRUE(status.has_value());
  EXPECT_GT(status->updates(), 1000u);
  EXPECT_EQ(status->law().to_string(), "gp");
}

// Rate commands end to end: the controller's φ̇ (--predict), the driver's ramp, the bench
// evaluating it at each sample's time. A deterministic rotation at 100 rad/s sampled at 2 kHz
// moves ~0.05 rad per sample; without prediction the loop's ~1 ms delay leaves ~3–4° (the
// benchmark measures it), with rate commands a few hundredths of a degree.
TEST_F(BenchProcessTest, RateCommandsTrackARotationAcrossProcesses) {
  StartObserver(46);
  StartDriver();
  StartController("A", 0, {"--predict"});
  const std::string scenario = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_rotation.pbtxt";
  ChildProcess& polarimeter =
      StartPolarimeter({scenario, "--rate-hz", "2000", "--rate-rad-per-s", "100", "--run-s", "4", "--json"});
  ASSERT_EQ(polarimeter.Wait(30s), 0) << Logs();
  const nlohmann::json report = LastJsonLine(polarimeter.Log());
  ASSERT_TRUE(report.is_object()) << Logs();
  ASSERT_FALSE(report["lock_time_s"].is_null()) << report.dump(2);
  EXPECT_LT(report["error_deg"]["mean"].get<double>(), 1.0) << report.dump(2);
  EXPECT_EQ(report["bench"]["rejected_states"].get<int>(), 0);
  // The driver ramped: its states carry the rate and a ramp that starts at the sample's time.
  size_t ramping = 0;
  for (const SeenState& seen : States()) {
    const msg::WaveplateState& s = seen.state;
    if (s.mode() != msg::DRIVER_ACTIVE || s.phi_rate_per_s().empty()) continue;
    ++ramping;
    EXPECT_EQ(s.ramp_start_time_ns(), s.sample_time_ns());
    EXPECT_GT(s.ramp_end_time_ns(), s.ramp_start_time_ns());
  }
  EXPECT_GT(ramping, 4000u);
  const auto status = Status("A");
  ASSERT_TRUE(status.has_value());
  EXPECT_NE(status->condition().to_string().find("ramping with the input at 100 rad/s"), std::string::npos)
      << status->condition().to_string();
}

/// The rows of a trace CSV (comment and header lines skipped).
std::vector<std::vector<double>> ReadTrace(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<double> row;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST_F(BenchProcessTest, LockstepAcrossProcessesReproducesDpcSim) {
  // The paper's 3-stage device and scrambler (100 krad/s at 50 MHz, 50 samples of delay), 0.1 ms
  // from activation on: 5 000 samples published and answered across three processes.
  const std::string scenario = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/paper_fig3.pbtxt";
  const std::vector<std::string> common = {"--duration-s", "2.1e-3", "--activation-s", "2e-3", "--noise-deg", "0.05"};
  StartObserver(41);
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), scenario);
    args.insert(args.end(), common.begin(), common.end());
    return args;
  };
  StartDriver(with({}));
  StartController("A", 0, with({}));
  const std::string bench_trace = dir_ + "/lockstep.csv";
  ChildProcess& polarimeter = StartPolarimeter(with({"--lockstep", "--trace", bench_trace, "--json"}));
  ASSERT_EQ(polarimeter.Wait(60s), 0) << Logs();

  const std::string sim_trace = dir_ + "/sim.csv";
  std::vector<std::string> sim_args = with({"--trace", sim_trace, "--trace-every", "1", "--json"});
  sim_args.insert(sim_args.begin(), "sim");
  sim_args.insert(sim_args.begin(), DPC_BINARY);
  ChildProcess sim(sim_args, dir_ + "/sim.log");
  ASSERT_EQ(sim.Wait(30s), 0) << sim.Log();

  const auto bench_rows = ReadTrace(bench_trace);
  const auto sim_rows = ReadTrace(sim_trace);
  ASSERT_EQ(bench_rows.size(), 105000u);
  ASSERT_EQ(sim_rows.size(), bench_rows.size());
  double worst = 0.0;
  for (size_t i = 0; i < sim_rows.size(); ++i) worst = std::max(worst, MaxAbsDifference(bench_rows[i], sim_rows[i]));
  EXPECT_LT(worst, 1e-9) << "trajectories differ";
  const nlohmann::json bench = LastJsonLine(polarimeter.Log());
  const nlohmann::json simulated = LastJsonLine(sim.Log());
  EXPECT_NEAR(bench["error_deg"]["mean"].get<double>(), simulated["error_deg"]["mean"].get<double>(), 1e-9);
  EXPECT_EQ(bench["bench"]["published"].get<int>(), 5000);
}

TEST_F(BenchProcessTest, HigherPriorityControllerTakesOverWithoutAJump) {
  StartObserver(42);
  StartDriver();
  StartController("low", 0);
  StartPolarimeter({"--rate-hz", "2000"});
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("low") > 2000; }, 20s)) << Logs();  // ~1 s locked
  const size_t before = StateCount();
  StartController("high", 10);
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("high") > 200; }, 20s)) << Logs();
  const auto states = States();
  // The largest step of any stage between consecutive applied states: while tracking, and at
  // the switch. Bumpless: the switch is no larger than a tracking step (plus a margin).
  double tracking_step = 0.0, switch_step = 0.0;
  for (size_t i = std::max<size_t>(before, 1); i < states.size(); ++i) {
    const auto& a = states[i - 1].state;
    const auto& b = states[i].state;
    const double step = MaxAbsDifference(a.phi_applied(), b.phi_applied());
    if (a.obeyed_controller_id() != b.obeyed_controller_id()) {
      switch_step = std::max(switch_step, step);
    } else {
      tracking_step = std::max(tracking_step, step);
    }
  }
  EXPECT_TRUE(SoonObeys("high")) << LatestState()->reason().to_string();
  EXPECT_LT(switch_step, std::max(0.02, 2.0 * tracking_step))
      << "tracking step " << tracking_step << ", switch step " << switch_step;
  const auto status = Status("low");
  ASSERT_TRUE(status.has_value());
  EXPECT_FALSE(status->obeyed());
}

TEST_F(BenchProcessTest, KillNineOfTheObeyedControllerHandsControlToTheStandby) {
  StartObserver(43);
  StartDriver();
  ChildProcess& primary = StartController("primary", 10);
  StartController("standby", 0);
  StartPolarimeter({"--rate-hz", "5000"});
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("primary") > 2000; }, 20s)) << Logs();
  primary.Signal(SIGKILL);
  const size_t standby_before = AppliedBy("standby");  // a loaded machine may have switched briefly
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("standby") > standby_before + 500; }, 10s)) << Logs();
  // The failover gap: from the last command of the killed controller the driver applied to the
  // first of the standby's (driver receive times, wall clock).
  const auto states = States();
  // (A loaded machine may have switched briefly before: look after the primary's last state.)
  int64_t last_primary_ns = 0, first_standby_ns = 0;
  size_t last_primary = 0;
  for (size_t i = 0; i < states.size(); ++i) {
    const auto& s = states[i].state;
    if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "primary") {
      last_primary_ns = s.command_receive_time_ns();
      last_primary = i;
    }
  }
  double switch_step = 0.0;
  for (size_t i = last_primary + 1; i < states.size(); ++i) {
    const auto& s = states[i].state;
    // (The driver's own switch notice repeats the primary's last command: skip it.)
    if (s.answers_sample() > 0 && s.obeyed_controller_id().to_string() == "standby" &&
        s.command_receive_time_ns() > last_primary_ns) {
      first_standby_ns = s.command_receive_time_ns();
      switch_step = MaxAbsDifference(states[last_primary].state.phi_applied(), s.phi_applied());
      break;
    }
  }
  ASSERT_GT(first_standby_ns, last_primary_ns);
  const double gap_ms = static_cast<double>(first_standby_ns - last_primary_ns) * 1e-6;
  std::printf("failover gap after kill -9: %.2f ms, step at the switch %.4f\n", gap_ms, switch_step);
  EXPECT_LE(gap_ms, 10.0);
  // Bumpless, seen where it matters, at the output: no error spike after the switch. (The step
  // in φ is not a good measure: the input keeps turning during the gap, and a starved primary
  // may have lagged, so the standby's first command legitimately corrects that.) A standby that
  // continued from a φ of its own jumped by 0.24 to 0.96 in φ, tens of degrees at the output.
  const double before_deg = MaxErrorDeg(last_primary_ns - 200'000'000, last_primary_ns);
  const double after_deg = MaxErrorDeg(first_standby_ns, first_standby_ns + 100'000'000);
  std::printf("largest output error: %.2f° in the 200 ms before the kill, %.2f° in the 100 ms after the switch\n",
              before_deg, after_deg);
  // While nobody commands (the gap, and any stall of the machine right after the kill), the
  // driver holds φ and the input keeps turning at the scrambler's rate (20 rad/s in the embedded
  // bench_default.pbtxt): that drift is the hold's, not a bump of the standby. Seen in CI: a
  // 2.2-ms gap followed by a 6.9° peak (1.9° before), with a φ step of 0.003 at the switch.
  constexpr double kScramblerRateRadPerS = 20.0;
  const double hold_drift_deg = kScramblerRateRadPerS * gap_ms * 1e-3 * 180.0 / M_PI;
  EXPECT_LT(after_deg, std::max(5.0, 2.0 * before_deg) + hold_drift_deg) << "hold drift " << hold_drift_deg << "°";
  EXPECT_TRUE(SoonObeys("standby")) << LatestState()->reason().to_string();
}

TEST_F(BenchProcessTest, WithoutAControllerTheDriverHoldsAndReportsThenResumes) {
  // A still input: the held φ stays right, so a resuming controller has nothing to correct and
  // any step it makes is a bump.
  StartObserver(44);
  StartDriver();
  ChildProcess& only = StartController("only", 0);
  StartPolarimeter({"--rate-hz", "2000", "--static"});
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("only") > 1000; }, 20s)) << Logs();
  only.Signal(SIGKILL);
  ASSERT_TRUE(WaitUntil([&] {
    auto s = LatestState();
    return s && s->mode() == msg::DRIVER_HOLDING;
  }, 5s)) << Logs();
  const msg::WaveplateState holding = *LatestState();
  EXPECT_NE(holding.reason().to_string().find("only silent"), std::string::npos) << holding.reason().to_string();
  // While holding, heartbeats repeat the same φ.
  const size_t count = StateCount();
  ASSERT_TRUE(WaitUntil([&] { return StateCount() > count + 3; }, 5s));
  const auto held = LatestState();
  EXPECT_EQ(held->mode(), msg::DRIVER_HOLDING);
  EXPECT_EQ(held->phi_applied(), holding.phi_applied());
  // A new controller resumes from the held φ.
  const size_t before = StateCount();
  StartController("next", 0);
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("next") > 100; }, 20s)) << Logs();
  const auto states = States();
  for (size_t i = before; i < states.size(); ++i) {
    if (states[i].state.obeyed_controller_id().to_string() == "next" && states[i].state.answers_sample() > 0) {
      EXPECT_LT(MaxAbsDifference(states[i].state.phi_applied(), holding.phi_applied()), 0.05)
          << "the first command of the new controller jumped: state " << i - before << " after "
          << "the hold; " << Logs();
      break;
    }
  }
}

TEST_F(BenchProcessTest, MalformedCommandsAndSamplesAreCountedAndNeverApplied) {
  StartObserver(45);
  StartDriver();
  StartController("A", 0);
  StartPolarimeter({"--rate-hz", "1000"});
  ASSERT_TRUE(WaitUntil([&] { return AppliedBy("A") > 200; }, 20s)) << Logs();
  auto commands = participant_->MakeWriter<msg::WaveplateCommand>();
  auto samples = participant_->MakeWriter<msg::StokesSample>();
  ASSERT_TRUE(WaitUntil([&] { return commands->matched_readers() > 0 && samples->matched_readers() > 0; }, 10s));
  auto bad_command = [](std::vector<double> phi) {
    msg::WaveplateCommand c;
    c.bench_id("bench1");
    c.controller_id("intruder");
    c.priority(100);  // would win if it were valid
    c.answers_sample(1);
    c.phi(std::move(phi));
    return c;
  };
  // One at a time, re-sent every 50 ms until counted: the periodic topics are best effort and
  // keep only the latest sample, so a write may be lost or replaced.
  auto write_until = [](const std::function<void()>& write, const std::function<bool()>& counted) {
    for (int attempt = 0; attempt < 100; ++attempt) {
      write();
      if (WaitUntil(counted, 50ms)) return true;
    }
    return false;
  };
  for (const auto& phi : {std::vector<double>{NAN, 0.0, 0.0}, std::vector<double>{0.1, 0.2},
                          std::vector<double>(17, 0.0), std::vector<double>{INFINITY, 0.0, 0.0}}) {
    const uint64_t rejected_before = LatestState()->commands_rejected();
    ASSERT_TRUE(write_until([&] { commands->Write(bad_command(phi)); },
                            [&] { return LatestState()->commands_rejected() > rejected_before; }))
        << phi.size() << " values: " << Logs();
  }
  EXPECT_TRUE(SoonObeys("A")) << LatestState()->reason().to_string();
  const auto state = LatestState();
  for (double v : state->phi_applied()) EXPECT_TRUE(std::isfinite(v));
  EXPECT_FALSE(state->last_rejection().to_string().empty());

  msg::StokesSample sample;
  sample.bench_id("bench1");
  sample.sequence_number(1);
  sample.s_in({1.0, 1.0, 0.0});   // not unit
  sample.s_out({1.0, 0.0, 0.0});
  ASSERT_TRUE(write_until([&] { samples->Write(sample); }, [&] {
    auto status = Status("A");
    return status && status->rejected_samples() >= 1;
  })) << Logs();
  sample.s_in({NAN, 0.0, 0.0});
  const uint64_t rejected_samples = Status("A")->rejected_samples();
  ASSERT_TRUE(write_until([&] { samples->Write(sample); }, [&] {
    auto status = Status("A");
    return status && status->rejected_samples() > rejected_samples;
  })) << Logs();
  EXPECT_NE(Status("A")->last_rejection().to_string().find("s_in"), std::string::npos);
  // The loop kept running on the good samples.
  const size_t applied = AppliedBy("A");
  EXPECT_TRUE(WaitUntil([&] { return AppliedBy("A") > applied + 100; }, 5s));
}

}  // namespace
}  // namespace dpc
