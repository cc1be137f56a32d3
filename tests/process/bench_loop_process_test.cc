// The bench's loop as real processes on loopback: dpc-polarimeter, dpc-controller and dpc-driver
// lock over Fast DDS, rate commands track a rotation, and a lockstep run reproduces `dpc sim`.
// Every test uses its own DDS domain (40–59, 75; 59: bench_failover) and ends every process it
// started.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/bench_fixture.h"
#include "support/json_lines.h"

namespace dpc {
namespace {

using dpc::testing::Eventually;
using dpc::testing::LastJsonLine;
using dpc::testing::Process;
using dpc::testing::SeenState;
using dpc::testing::Slurp;
using namespace std::chrono_literals;

class BenchLoopTest : public dpc::testing::BenchFixture {};

double MaxAbsDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
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

TEST_F(BenchLoopTest, ThreeServicesLockOnLoopback) {
  StartObserver(40);
  StartDriver();
  StartController("A", 0);
  Process& polarimeter = StartPolarimeter({"--rate-hz", "2000", "--run-s", "4", "--json"});
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
  // A quarter of the 8000 samples: with a parallel ctest beside it on two cores the loop
  // answered 3998 (the rates the bench sustains are measured in bench/).
  EXPECT_GT(loop["count"].get<int64_t>(), 2000) << latency.dump(2);
  EXPECT_GT(latency["sample_to_command_at_driver"]["p50"].get<double>(), 0.0) << latency.dump(2);
  EXPECT_LE(latency["sample_to_command_at_driver"]["p50"].get<double>(),
            latency["sample_to_state_published"]["p50"].get<double>());
  EXPECT_LE(latency["sample_to_state_published"]["p50"].get<double>(), loop["p50"].get<double>());
  EXPECT_LE(loop["p50"].get<double>(), loop["p99"].get<double>());
  EXPECT_EQ(latency["implausible"].get<int>(), 0);
  EXPECT_GT(AppliedBy("A"), 2000u);
  const auto status = Status("A");
  ASSERT_TRUE(status.has_value());
  EXPECT_GT(status->updates(), 1000u);
  EXPECT_EQ(status->law().to_string(), "gp");
}

// Rate commands end to end: the controller's φ̇ (--predict), the driver's ramp, the bench
// evaluating it at each sample's time. A deterministic rotation at 100 rad/s sampled at 2 kHz
// moves ~0.05 rad per sample; without prediction the loop's ~1 ms delay leaves ~3–4° (the
// benchmark measures it), with rate commands a few hundredths of a degree.
TEST_F(BenchLoopTest, RateCommandsTrackARotationAcrossProcesses) {
  StartObserver(46);
  StartDriver();
  StartController("A", 0, {"--predict"});
  const std::string scenario = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/bench_rotation.pbtxt";
  Process& polarimeter =
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

TEST_F(BenchLoopTest, TheRangeCriterionKeepsASlowBenchsChannelsInsideTheirRanges) {
  // The emulator's device in volts (±10 V, simulated) at 500 Hz with one sample of delay: too
  // slow for the paper's null-space pull to hold phi against the scrambler. In lockstep (so the
  // run is dpc sim's, seed 1, whatever the machine's load) channel 2 reaches -10 V and the error
  // 92.7° within 15 s without the range criterion. The criterion, given to every service,
  // reaches the controller's law through the driver's device description and keeps every
  // channel inside: down to -8.3 V, max error 11.9°. (In real time the trajectory depends on
  // the timing; over 60 seeds of dpc sim the criterion still touched a limit in 2.)
  const std::string source = std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/emulator_epc.pbtxt";
  std::string scenario_text = Slurp(source);
  // The dithering baseline's reset lasts at least one sample: one sample at 500 Hz.
  const std::string reset = "reset_duration_s: 1e-4";
  const size_t at = scenario_text.find(reset);
  ASSERT_NE(at, std::string::npos) << source;
  scenario_text.replace(at, reset.size(), "reset_duration_s: 2e-3");
  const std::string scenario = dir_ + "/emulator_epc_500hz.pbtxt";
  std::ofstream(scenario) << scenario_text;
  auto with = [&](std::vector<std::string> args) {
    const std::vector<std::string> common = {
        scenario, "--range", "10", "--sample-rate-hz", "500", "--delay-s", "2e-3", "--duration-s", "15"};
    args.insert(args.begin(), common.begin(), common.end());
    return args;
  };
  StartObserver(75);
  StartDriver(with({}));
  StartController("A", 0, with({}));
  Process& polarimeter = StartPolarimeter(with({"--lockstep", "--json"}));
  ASSERT_EQ(polarimeter.Wait(120s), 0) << Logs();
  const nlohmann::json report = LastJsonLine(polarimeter.Log());
  ASSERT_TRUE(report.is_object()) << Logs();
  ASSERT_FALSE(report["lock_time_s"].is_null()) << report.dump(2);
  EXPECT_TRUE(report["range_criterion"].get<bool>()) << report.dump(2);
  // The loop's steady lag behind 20 rad/s at 500 Hz with step 0.5 is 4.6°.
  EXPECT_LT(report["error_deg"]["p50"].get<double>(), 7.0) << report.dump(2);
  EXPECT_LT(report["error_deg"]["max"].get<double>(), 20.0) << report.dump(2);
  ASSERT_EQ(report["phi_min"].size(), 3u) << report.dump(2);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(report["phi_min"][c].get<double>(), -9.0) << c << report.dump(2);
    EXPECT_LT(report["phi_max"][c].get<double>(), 9.0) << c << report.dump(2);
  }
}

TEST_F(BenchLoopTest, LockstepAcrossProcessesReproducesDpcSim) {
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
  Process& polarimeter = StartPolarimeter(with({"--lockstep", "--trace", bench_trace, "--json"}));
  ASSERT_EQ(polarimeter.Wait(60s), 0) << Logs();

  const std::string sim_trace = dir_ + "/sim.csv";
  std::vector<std::string> sim_args = with({"--trace", sim_trace, "--trace-every", "1", "--json"});
  sim_args.insert(sim_args.begin(), "sim");
  sim_args.insert(sim_args.begin(), DPC_BINARY);
  Process sim(sim_args, dir_ + "/sim.log");
  ASSERT_EQ(sim.Wait(30s), 0) << sim.Log();

  const auto bench_rows = ReadTrace(bench_trace);
  const auto sim_rows = ReadTrace(sim_trace);
  ASSERT_EQ(bench_rows.size(), 105000u);
  ASSERT_EQ(sim_rows.size(), bench_rows.size());
  double worst = 0.0;
  size_t first_different = sim_rows.size();
  for (size_t i = 0; i < sim_rows.size(); ++i) {
    const double difference = MaxAbsDifference(bench_rows[i], sim_rows[i]);
    if (difference >= 1e-9 && first_different == sim_rows.size()) first_different = i;
    worst = std::max(worst, difference);
  }
  EXPECT_LT(worst, 1e-9) << "trajectories differ from trace row " << first_different << "\n" << Logs();
  const nlohmann::json bench = LastJsonLine(polarimeter.Log());
  const nlohmann::json simulated = LastJsonLine(sim.Log());
  EXPECT_NEAR(bench["error_deg"]["mean"].get<double>(), simulated["error_deg"]["mean"].get<double>(), 1e-9);
  EXPECT_EQ(bench["bench"]["published"].get<int>(), 5000);

  // The polarimeter's trace carries dpc sim's header: dpc plot draws it as it draws a sim trace.
  Process plot({DPC_BINARY, "plot", bench_trace, "-o", dir_ + "/lockstep.png"}, dir_ + "/plot.log");
  ASSERT_EQ(plot.Wait(60s), 0) << plot.Log();
  EXPECT_GT(std::filesystem::file_size(dir_ + "/lockstep.png"), 10000u);
}

}  // namespace
}  // namespace dpc
