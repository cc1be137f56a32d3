// End-to-end tests of the dpc command: they run the built binary (DPC_BINARY) on the shipped
// scenarios and on broken ones, and check its output, files and exit codes.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/command_line_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

using dpc::testing::Result;
using dpc::testing::Slurp;

class DpcCliTest : public dpc::testing::CommandLineTest {
 protected:
  Result Run(const std::string& args) { return Dpc(args); }
  // A valid minimal scenario with `extra` appended (later fields override nothing: text format
  // rejects repeated singular fields, so tests write whole messages).
  static std::string Minimal(const std::string& stages, const std::string& rest = "") {
    return stages + "\ninput { disturbances { paper_scrambler { rate_rad_per_s: 1e4 } } }\n" +
           "simulation { duration_s: 1e-4 }\ncontroller { activation_s: 0 }\n" + rest;
  }
};

TEST_F(DpcCliTest, ShippedBenchScenariosRunAndLock) {
  // The real-time bench's scenarios, simulated for 0.5 s at their 10 kHz (one sample of delay).
  for (const char* name : {"bench_default", "bench_rotation", "bench_paper_diffusion"}) {
    const Result r = Run("sim " + Scenario(name) + " --duration-s 0.5 --json");
    ASSERT_EQ(r.exit_code, 0) << name << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["samples"], 5000) << name;
    ASSERT_FALSE(j["lock_time_s"].is_null()) << name;
    EXPECT_LT(j["error_deg"]["mean"].get<double>(), 1.0) << name;
  }
}

TEST_F(DpcCliTest, ShippedPaperScenariosLockAndKeepPhiBounded) {
  for (const char* name : {"paper_fig3", "paper_fig4", "paper_fig5"}) {
    const Result r = Run("sim " + Scenario(name) + " --json");
    ASSERT_EQ(r.exit_code, 0) << name << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["samples"], 500000) << name;
    ASSERT_FALSE(j["lock_time_s"].is_null()) << name;  // locked at the end
    // The first lock (lock_time_s is the last relock: after any excursion of the run).
    ASSERT_FALSE(j["first_lock_time_s"].is_null()) << name;
    EXPECT_LT(j["first_lock_time_s"].get<double>(), 1e-3) << name;
    EXPECT_LT(j["error_deg"]["mean"].get<double>(), 8.0) << name;
    for (const char* key : {"phi_min", "phi_max"}) {
      for (const auto& v : j[key]) EXPECT_LT(std::abs(v.get<double>()), 3.0) << name << " " << key;
    }
    for (const char* key : {"error_deg", "extinction_db_mean", "first_lock_time_s", "phi_p1",
                            "phi_p99", "nullspace_active_fraction", "resets", "samples_per_s"}) {
      EXPECT_TRUE(j.contains(key)) << key;
    }
  }
}

TEST_F(DpcCliTest, ShippedStressScenariosRecoverWithoutResets) {
  // The lightning stroke (5.1 Mrad/s for 10 µs at 10 ms): felt (the error goes far above the
  // lock threshold), no reset, φ bounded, and back below 40 dB within 1 ms (97 µs measured).
  const Result lightning = Run("sim " + Scenario("stress_lightning") + " --json");
  ASSERT_EQ(lightning.exit_code, 0) << lightning.err;
  const auto l = nlohmann::json::parse(lightning.out);
  EXPECT_GT(l["error_deg"]["max"].get<double>(), 90.0);
  EXPECT_EQ(l["resets"], 0);
  EXPECT_LT(l["error_deg"]["p50"].get<double>(), 1.0);
  EXPECT_GE(l["recovery"]["stretches_above"].get<int>(), 1);
  EXPECT_LT(l["recovery"]["longest_above_s"].get<double>(), 1e-3);
  const double from_s = l["recovery"]["longest_above_from_s"].get<double>();
  EXPECT_GE(from_s, 10e-3);  // the stroke's, not the lock-in's
  EXPECT_LT(from_s, 10.1e-3);
  for (const char* key : {"phi_min", "phi_max"}) {
    for (const auto& v : l[key]) EXPECT_LT(std::abs(v.get<double>()), 3.0) << key;
  }
  // 2 Mrad/s deterministic rotation, 20 ms of it: tracked below 2° throughout.
  const Result rotation = Run("sim " + Scenario("stress_rotation_2mrad") + " --duration-s 0.02 --json");
  ASSERT_EQ(rotation.exit_code, 0) << rotation.err;
  const auto r = nlohmann::json::parse(rotation.out);
  EXPECT_LT(r["error_deg"]["max"].get<double>(), 2.0);
  EXPECT_EQ(r["resets"], 0);
  // The 1e9-sample run, 20 ms of it: the scenario loads and tracks (the whole run is a benchmark).
  const Result scrambling = Run("sim " + Scenario("stress_scrambling_60krad_1e9") + " --duration-s 0.02 --json");
  ASSERT_EQ(scrambling.exit_code, 0) << scrambling.err;
  const auto c = nlohmann::json::parse(scrambling.out);
  EXPECT_EQ(c["samples"], 1000000);
  EXPECT_LT(c["error_deg"]["max"].get<double>(), 11.9);  // 0.208 rad
}

TEST_F(DpcCliTest, ShippedTemperatureCalibrationRunsAtAnyCalibratedTemperatureOnly) {
  // The maps are interpolated between the tables at 25 and 35 °C; the scenario's seed is fixed,
  // so another operating temperature (another device) gives another run.
  const Result at_30 = Run("sim " + Scenario("emulator_epc_by_temperature") +
                           " --duration-s 0.5 --operating-temperature-c 30 --json");
  ASSERT_EQ(at_30.exit_code, 0) << at_30.err;
  const Result at_25 = Run("sim " + Scenario("emulator_epc_by_temperature") + " --duration-s 0.5 --json");
  ASSERT_EQ(at_25.exit_code, 0) << at_25.err;
  const auto a = nlohmann::json::parse(at_30.out), b = nlohmann::json::parse(at_25.out);
  EXPECT_LT(a["error_deg"]["p50"].get<double>(), 1.0);
  EXPECT_NE(a["phi_max"], b["phi_max"]);
  const Result outside = Run("sim " + Scenario("emulator_epc_by_temperature") + " --operating-temperature-c 40");
  EXPECT_EQ(outside.exit_code, 2);
  EXPECT_NE(outside.err.find("stages[0].map.tables_by_condition.operating_temperature_c: 40 °C is outside the "
                             "calibrated 15–35 °C"),
            std::string::npos)
      << outside.err;
  EXPECT_NE(outside.err.find("(set by --operating-temperature-c)"), std::string::npos) << outside.err;
}

TEST_F(DpcCliTest, TheRangeCriterionKeepsAVoltDeviceInsideAndLockedAsTheDefaultDoes) {
  // The emulator's device in volts (±10 V): with --range the null-space pull near the centre is
  // the default's, so the loop tracks as well, and no command ever reaches an end.
  const Result plain = Run("sim " + Scenario("emulator_epc") + " --duration-s 2 --json");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const Result ranged = Run("sim " + Scenario("emulator_epc") + " --duration-s 2 --range 10 --json");
  ASSERT_EQ(ranged.exit_code, 0) << ranged.err;
  const auto a = nlohmann::json::parse(plain.out), b = nlohmann::json::parse(ranged.out);
  EXPECT_LT(b["error_deg"]["p99"].get<double>(), 1.2 * a["error_deg"]["p99"].get<double>()) << ranged.out;
  EXPECT_LT(b["error_deg"]["max"].get<double>(), 2.0) << ranged.out;
  EXPECT_EQ(b["clamped_updates"], 0) << ranged.out;
  for (const auto& phi : b["phi_max"]) EXPECT_LT(phi.get<double>(), 9.0) << ranged.out;
  for (const auto& phi : b["phi_min"]) EXPECT_GT(phi.get<double>(), -9.0) << ranged.out;
}

TEST_F(DpcCliTest, AThresholdTheRangesNeverLetTheControlsReachIsRefused) {
  // paper_fig5: gpt with threshold 1; --range 1 keeps every |phi_i| <= 1.
  const Result r = Run("sim " + Scenario("paper_fig5") + " --range 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("controller.threshold: gpt runs the null-space term only while some |phi_i| > 1"),
            std::string::npos)
      << r.err;
  const Result wider = Run("sim " + Scenario("paper_fig5") + " --range 1.5 --duration-s 0.003");
  EXPECT_EQ(wider.exit_code, 0) << wider.err;
}

TEST_F(DpcCliTest, AFlagTheLawDoesNotUseIsWarnedAbout) {
  const Result r = Run("sim --method gp --threshold 0.5 --duration-s 0.003");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("dpc sim: warning: --threshold applies to gpt; method gp ignores it"), std::string::npos)
      << r.err;
  const Result used = Run("sim --method gpt --threshold 0.5 --duration-s 0.003");
  EXPECT_EQ(used.exit_code, 0) << used.err;
  EXPECT_EQ(used.err.find("warning"), std::string::npos) << used.err;
}

TEST_F(DpcCliTest, ThresholdedScenarioUsesTheNullSpaceOnlyPartOfTheTime) {
  const Result r = Run("sim " + Scenario("paper_fig5") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double fraction = nlohmann::json::parse(r.out)["nullspace_active_fraction"];
  EXPECT_GT(fraction, 0.0);
  EXPECT_LT(fraction, 0.9);
}

TEST_F(DpcCliTest, TraceAndPlotAreWritten) {
  const std::string png = (dir_ / "fig.png").string(), csv = (dir_ / "fig.csv").string();
  const Result r = Run("sim " + Scenario("paper_fig3") + " --duration-s 3e-3 --trace " + csv +
                       " --plot " + png);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("lock"), std::string::npos);
  std::ifstream in(png, std::ios::binary);
  std::array<char, 8> signature{};
  in.read(signature.data(), 8);
  EXPECT_EQ(std::string(signature.data() + 1, 3), "PNG");
  const std::string trace = Slurp(csv);
  EXPECT_EQ(trace.rfind("# dpc-trace", 0), 0u);
  EXPECT_NE(trace.find("t_s,s_in_1"), std::string::npos);
  // The plot command redraws it.
  const Result again = Run("plot " + csv + " -o " + (dir_ / "again.png").string());
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(dir_ / "again.png"));
}

TEST_F(DpcCliTest, FlagsOverrideTheScenario) {
  const Result r = Run("sim --stages-axes 3131 --method pinv --rate-rad-per-s 2e4 --duration-s 3e-3 "
                       "--delay-s 2e-7 --seed 5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["stages"], "R3 R1 R3 R1");
  EXPECT_EQ(j["method"], "pinv");
  EXPECT_EQ(j["rate_rad_per_s"], 2e4);
  EXPECT_EQ(j["delay_samples"], 10);
  EXPECT_EQ(j["seed"], 5);
  EXPECT_EQ(j["samples"], 150000);
}

TEST_F(DpcCliTest, StaticInputLocksExactly) {
  const Result r = Run("sim --static --duration-s 3e-3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(nlohmann::json::parse(r.out)["error_deg"]["p99"].get<double>(), 1e-6);
}

TEST_F(DpcCliTest, MeasuredLoopAboveItsLimitWarns) {
  const Result r = Run("sim --loop measured --duration-s 2.1e-3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("stability limit"), std::string::npos) << r.err;
}

TEST_F(DpcCliTest, PrintScenarioRoundTrips) {
  const Result r = Run("sim " + Scenario("paper_fig4") + " --step 0.2 --print-scenario");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string path = Write("printed.pbtxt", r.out);
  const Result again = Run("sim " + path + " --duration-s 2.5e-3 --json");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(nlohmann::json::parse(again.out)["step"], 0.2);
}

struct InvalidCase {
  const char* name;
  std::string text;
  const char* field;  // must appear in the message
};

TEST_F(DpcCliTest, InvalidScenariosAreRejectedNamingTheField) {
  std::string seventeen;
  for (int i = 0; i < 17; ++i) seventeen += "stages { axis: S1 }\n";
  const std::vector<InvalidCase> cases{
      {"nan", Minimal("stages { axis: S1 } stages { axis_vector { s1: nan s2: 1 } }"),
       "stages[1].axis_vector"},
      {"zero_axis", Minimal("stages { axis: S1 } stages { axis_vector { s1: 0 s2: 0 s3: 0 } }"),
       "stages[1].axis_vector"},
      {"unknown_method", "stages { axis: S1 }\ncontroller { method: NEWTON }", "method"},
      {"negative_rate",
       "stages { axis: S1 }\ninput { disturbances { paper_scrambler { rate_rad_per_s: -5 } } }",
       "input.disturbances[0].paper_scrambler.rate_rad_per_s"},
      {"no_stages", "input { }", "stages"},
      {"seventeen_stages", seventeen, "stages"},
      {"table_not_monotonic",
       Minimal("stages { axis: S1 map { table { control: [0, 1, 2, 3] "
               "angle_rad: [0, 1, 3, 2] } } }"),
       "stages[0].map.table.angle_rad[3]"},
      {"non_unit_target", Minimal("stages { axis: S1 }", "target { point { s1: 0 s2: 0.6 s3: 0.9 } }"),
       "target.point"},
      {"syntax", "stages { axis: S1 ", "syntax.pbtxt:1"},
  };
  for (const auto& c : cases) {
    const std::string path = Write(std::string(c.name) + ".pbtxt", c.text);
    const Result r = Run("sim " + path + " --json");
    EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.out << r.err;
    EXPECT_NE(r.err.find(c.field), std::string::npos) << c.name << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.name;
  }
}

TEST_F(DpcCliTest, BadFlagsAreRejectedNamingTheFlag) {
  Result r = Run("sim --method newton");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--method"), std::string::npos) << r.err;
  r = Run("sim --step -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("controller.step"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--step"), std::string::npos) << r.err;
  r = Run("sim --stages-axes 14");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--stages-axes"), std::string::npos) << r.err;
  r = Run("sim --static --rate-rad-per-s 5");
  EXPECT_EQ(r.exit_code, 2);
  r = Run("sim --method damped --stages-axes 3131");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("controller.method"), std::string::npos) << r.err;
  r = Run("sim /nonexistent.pbtxt");
  EXPECT_EQ(r.exit_code, 2);
  r = Run("frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  // Values CLI11 would otherwise take: a negative seed wraps to 2^64 − 1, an empty rate list
  // becomes 0 rad/s, no or a negative number of workers.
  r = Run("sim --seed -1 --duration-s 1e-4");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
  r = Dpc({"sweep", "--rates", "", "--duration-s", "1e-4"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--rates"), std::string::npos) << r.err;
  // A rate of NaN was taken (every comparison with it is false) and ran as "rate nan".
  r = Dpc({"sweep", "--rates", "1e5,nan", "--duration-s", "1e-4"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--rates: 'nan' is not a finite number"), std::string::npos) << r.err;
  // So was a lock threshold of NaN (the monitor would never have said LOCKED).
  r = Dpc({"monitor", "--lock-threshold-deg", "nan"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--lock-threshold-deg: 'nan' is not a finite number"), std::string::npos) << r.err;
  for (const char* jobs : {"0", "-3"}) {
    r = Dpc({"sweep", "--jobs", jobs, "--duration-s", "1e-4"});
    EXPECT_EQ(r.exit_code, 2) << jobs;
    EXPECT_NE(r.err.find("--jobs"), std::string::npos) << r.err;
  }
  r = Dpc({"sweep", "--seeds", "1,-2", "--duration-s", "1e-4"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seeds"), std::string::npos) << r.err;
}

TEST_F(DpcCliTest, SeedsRunOncePerSeedAndReportTheSpreadOverThem) {
  const Result r = Run("sim " + Scenario("paper_fig3") + " --duration-s 4e-3 --seeds 1-2,5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["seeds"], nlohmann::json({1, 2, 5}));
  EXPECT_EQ(j["runs_completed"], 3);
  ASSERT_EQ(j["runs"].size(), 3u);
  double sum = 0.0, lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(j["runs"][i]["seed"], j["seeds"][i]);
    const double mean = j["runs"][i]["error_deg"]["mean"].get<double>();
    sum += mean;
    lo = std::min(lo, mean);
    hi = std::max(hi, mean);
  }
  const auto& over = j["over_seeds"]["error_deg_mean"];
  EXPECT_NEAR(over["mean"].get<double>(), sum / 3.0, 1e-12);
  EXPECT_EQ(over["min"].get<double>(), lo);
  EXPECT_EQ(over["max"].get<double>(), hi);
  EXPECT_GT(over["sd"].get<double>(), 0.0) << "three seeds give three different runs";
  // The same run as a single `dpc sim --seed 5`.
  const Result single = Run("sim " + Scenario("paper_fig3") + " --duration-s 4e-3 --seed 5 --json");
  ASSERT_EQ(single.exit_code, 0) << single.err;
  EXPECT_EQ(nlohmann::json::parse(single.out)["error_deg"], j["runs"][2]["error_deg"]);
  // Text: one line per seed, then the spread; and the flags it cannot go with.
  const Result text = Run("sim " + Scenario("paper_fig3") + " --duration-s 4e-3 --seeds 1-2");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("seed 2"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("over 2 seeds"), std::string::npos) << text.out;
  EXPECT_EQ(Run("sim --seeds 1-2 --seed 3").exit_code, 2);
  EXPECT_EQ(Run("sim --seeds 1-2 --plot x.png").exit_code, 2);
  const Result bad = Run("sim --seeds 3-1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--seeds"), std::string::npos) << bad.err;
}

TEST_F(DpcCliTest, InfoSaysWhatARecordingHoldsAndWhetherItEndedProperly) {
  ASSERT_EQ(std::system((std::string(DPC_MCAP_SAMPLE_BINARY) + " " + dir_.string()).c_str()), 0);
  Result r = Run("info " + (dir_ / "sample-zstd.mcap").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["complete"]);
  EXPECT_EQ(j["messages"], 2000);
  EXPECT_NEAR(j["duration_s"].get<double>(), 0.1999, 1e-9);
  EXPECT_EQ(j["metadata"]["recorder"]["host"], "here");
  ASSERT_EQ(j["channels"].size(), 2u);
  EXPECT_EQ(j["channels"][0]["topic"], "dpc_stokes_sample");
  EXPECT_EQ(j["channels"][0]["schema"], "dpc::msg::StokesSample");
  EXPECT_EQ(j["channels"][0]["messages"], 1000);
  EXPECT_NEAR(j["channels"][0]["rate_hz"].get<double>(), 5000.0, 1e-6);
  EXPECT_NEAR(j["channels"][1]["largest_gap_s"].get<double>(), 2e-4, 1e-12);
  // Cut short (a recorder killed): what is before the cut is read, and the exit code says so.
  {
    std::ifstream in(dir_ / "sample-lz4.mcap", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir_ / "cut.mcap", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  r = Run("info " + (dir_ / "cut.mcap").string() + " --json");
  EXPECT_EQ(r.exit_code, 1);
  j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["complete"]);
  EXPECT_NE(j["problem"].get<std::string>().find("cut short"), std::string::npos) << j["problem"];
  EXPECT_GT(j["messages"].get<int>(), 500);
  EXPECT_LT(j["messages"].get<int>(), 2000);
  // Not a recording at all.
  std::ofstream(dir_ / "trace.csv") << "t_s,s_in_1\n0,1\n";
  r = Run("info " + (dir_ / "trace.csv").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("not an MCAP file"), std::string::npos) << r.err;
}

TEST_F(DpcCliTest, InterruptStopsALongRunAndKeepsWhatWasRecorded) {
  // 1e9 samples would take minutes; SIGINT once it has simulated for a second of CPU time ends
  // the run at the next progress check.
  const std::string csv = (dir_ / "long.csv").string();
  dpc::testing::Process dpc({DPC_BINARY, "sim", "--duration-s", "20", "--json", "--trace", csv, "--trace-every",
                             "100000"},
                            dir_ / "out", dir_ / "err");
  const auto data_rows = [&] {
    int rows = 0;
    std::istringstream lines(Slurp(csv));
    for (std::string line; std::getline(lines, line);) rows += !line.empty() && line[0] != '#' && line[0] != 't';
    return rows;
  };
  ASSERT_TRUE(dpc::testing::Eventually([&] { return dpc.cpu_seconds() >= 1.0; }, 60s)) << dpc.err();
  dpc.Signal(SIGINT);
  EXPECT_EQ(dpc.Wait(60s), 130) << dpc.err();
  const auto j = nlohmann::json::parse(dpc.out());
  EXPECT_TRUE(j["stopped_early"].get<bool>());
  const int64_t samples = j["samples"];
  EXPECT_GT(samples, 0);
  EXPECT_LT(samples, 1000000000);
  // The trace holds every 100 000th sample up to the stop: nothing recorded is lost.
  EXPECT_EQ(data_rows(), (samples + 99999) / 100000);
}

TEST_F(DpcCliTest, SweepPrintsATableAndJsonLines) {
  const Result r = Run("sweep --methods gp,pinv --rates 1e3,1e4 --seeds 1,2 --duration-s 1e-3 "
                       "--activation-s 2e-4 --no-progress --csv " + (dir_ / "s.csv").string() +
                       " --plot " + (dir_ / "s.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int rows = 0;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) rows += line.rfind("scenario", 0) == 0;
  EXPECT_EQ(rows, 4) << r.out;
  // How fast, and how (SIMD batches or one run per thread), on stderr.
  EXPECT_NE(r.err.find("dpc sweep: 8 runs, "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" M samples/s on "), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "s.png"));
  EXPECT_NE(Slurp(dir_ / "s.csv").find("error_deg_mean"), std::string::npos);
  const Result json = Run("sweep --methods gp --rates 1e3,1e4 --duration-s 1e-3 --activation-s "
                          "2e-4 --json --no-progress");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  std::istringstream jl(json.out);
  int objects = 0;
  for (std::string line; std::getline(jl, line);) {
    EXPECT_NO_THROW(nlohmann::json::parse(line)) << line;
    ++objects;
  }
  EXPECT_EQ(objects, 2);
}

}  // namespace
