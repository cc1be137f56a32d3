#include "dpc/cli/run_report.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace dpc::cli {
namespace {

constexpr double kTolerance = 1e-15;

// Every field of README.md's "dpc sim output" table.
const char* const kReadmeResultFields[] = {
    "error_deg", "extinction_db_mean", "extinction_db_power_mean", "lock_time_s",
    "first_lock_time_s", "excursions", "threshold_crossings", "recovery", "statistics_from_s", "statistics_to_s",
    "statistics_samples", "phi_min", "phi_max", "phi_p1", "phi_p99",
    "nullspace_active_fraction", "resets", "failed_updates", "rank_deficient_updates",
    "clamped_updates", "sigma_min_min", "near_singular_fraction", "samples", "samples_per_s"};

// The settings that identify a run (RunSettingsJson), including README's `loop_kernel`.
const char* const kSettingsFields[] = {
    "scenario", "stages", "controls", "method", "loop", "step", "nullspace_step", "prediction",
    "singularity_damping", "range_criterion", "curvature_correction", "target",
    "rate_rad_per_s", "sample_rate_hz", "delay_s", "delay_samples", "duration_s",
    "activation_s", "polarimeter_noise_deg", "seed", "loop_kernel"};

// A 10 000-sample run of the paper's scenario (100 krad/s scrambler, control from 0.04 ms).
class JsonReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scenario_ = PaperScenario("131");
    scenario_.simulation.duration_s = 2e-4;
    scenario_.controller.activation_s = 4e-5;
  }

  // The report of one run of `scenario_`.
  nlohmann::ordered_json Report(const std::vector<std::string>& warnings = {}) {
    ClosedLoopSimulator simulator(scenario_);
    const SimulationResult result = simulator.Run();
    return RunReportJson(DescribeRun(simulator), result, warnings);
  }

  ScenarioConfig scenario_;
};

TEST_F(JsonReportTest, SettingsDescribeTheRun) {
  scenario_.simulation.seed = 17;
  scenario_.simulation.polarimeter_noise_deg = 0.25;
  const ClosedLoopSimulator simulator(scenario_);
  const nlohmann::ordered_json j = RunSettingsJson(DescribeRun(simulator));
  for (const char* key : kSettingsFields) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j.size(), std::size(kSettingsFields));
  EXPECT_EQ(j["scenario"], "paper-131");
  EXPECT_EQ(j["stages"], simulator.chain().Describe());
  EXPECT_EQ(j["stages"], "R1 R3 R1");
  EXPECT_EQ(j["controls"], 3);
  EXPECT_EQ(j["method"], "gp");
  EXPECT_EQ(j["loop"], "model");
  EXPECT_NEAR(j["step"].get<double>(), 0.1, kTolerance);
  EXPECT_NEAR(j["nullspace_step"].get<double>(), 0.1, kTolerance);
  EXPECT_EQ(j["target"], simulator.target().Describe());
  EXPECT_NEAR(j["rate_rad_per_s"].get<double>(), 1e5, kTolerance);
  EXPECT_NEAR(j["sample_rate_hz"].get<double>(), 50e6, kTolerance);
  EXPECT_NEAR(j["delay_s"].get<double>(), 1e-6, kTolerance);
  EXPECT_EQ(j["delay_samples"], 50);
  EXPECT_NEAR(j["duration_s"].get<double>(), 2e-4, kTolerance);
  EXPECT_NEAR(j["activation_s"].get<double>(), 4e-5, kTolerance);
  EXPECT_NEAR(j["polarimeter_noise_deg"].get<double>(), 0.25, kTolerance);
  EXPECT_EQ(j["seed"], 17);
  EXPECT_EQ(j["loop_kernel"], "fast");
}

TEST_F(JsonReportTest, SettingsNameTheGeneralLoopAndTheMeasuredMode) {
  scenario_.controller.method = ControlMethod::kTranspose;
  scenario_.controller.loop = LoopMode::kMeasured;
  const ClosedLoopSimulator simulator(scenario_);
  ASSERT_FALSE(simulator.uses_fast_path());
  const nlohmann::ordered_json j = RunSettingsJson(DescribeRun(simulator));
  EXPECT_EQ(j["method"], "transpose");
  EXPECT_EQ(j["loop"], "measured");
  EXPECT_EQ(j["loop_kernel"], "general");
}

TEST_F(JsonReportTest, ReportHasEveryReadmeFieldAndTheSettings) {
  const nlohmann::ordered_json j = Report();
  for (const char* key : kReadmeResultFields) EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : kSettingsFields) EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : {"mean", "p50", "p99", "max"}) {
    EXPECT_TRUE(j["error_deg"].contains(key)) << key;
  }
  for (const char* key : {"wall_time_s", "stopped_early", "lock_threshold_deg",
                          "statistics_from_s", "statistics_samples", "updates", "final_phi",
                          "warnings"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  // The settings come first, in RunSettingsJson's order.
  EXPECT_EQ(j.begin().key(), "scenario");
}

TEST_F(JsonReportTest, ReportCarriesTheResults) {
  ClosedLoopSimulator simulator(scenario_);
  const SimulationResult result = simulator.Run();
  const nlohmann::ordered_json j = RunReportJson(DescribeRun(simulator), result, {});
  const RunSummary& r = result.summary;
  EXPECT_EQ(j["samples"], 10000);
  EXPECT_EQ(j["samples"], r.samples);
  EXPECT_EQ(j["stopped_early"], false);
  EXPECT_EQ(j["updates"], r.updates);
  EXPECT_EQ(j["statistics_samples"], r.statistics_samples);
  EXPECT_EQ(j["excursions"], r.excursions);
  EXPECT_EQ(j["threshold_crossings"], r.threshold_crossings);
  EXPECT_GE(r.threshold_crossings, r.excursions);
  EXPECT_NEAR(j["statistics_to_s"].get<double>(), r.statistics_end_s, kTolerance);
  EXPECT_EQ(j["failed_updates"], r.failed_updates);
  EXPECT_EQ(j["resets"], r.resets);
  EXPECT_NEAR(j["lock_threshold_deg"].get<double>(), 10.0, kTolerance);
  ASSERT_TRUE(r.lock_time_s.has_value()) << "the paper scenario locks within 0.16 ms";
  EXPECT_EQ(j["lock_time_s"].get<double>(), *r.lock_time_s);
  EXPECT_EQ(j["error_deg"]["mean"].get<double>(), r.error_deg.mean);
  EXPECT_EQ(j["error_deg"]["p99"].get<double>(), r.error_deg.p99);
  EXPECT_EQ(j["extinction_db_mean"].get<double>(), r.extinction_db_mean);
  EXPECT_EQ(j["sigma_min_min"].get<double>(), r.sigma_min_min);
  EXPECT_NEAR(j["nullspace_active_fraction"].get<double>(), 1.0, kTolerance);  // gp
  EXPECT_GT(j["samples_per_s"].get<double>(), 0.0);
  EXPECT_GT(j["wall_time_s"].get<double>(), 0.0);
}

TEST_F(JsonReportTest, ArraysHaveOneEntryPerControl) {
  for (const char* axes : {"131", "3131"}) {
    scenario_ = PaperScenario(axes);
    scenario_.simulation.duration_s = 1e-4;
    scenario_.controller.activation_s = 2e-5;
    const nlohmann::ordered_json j = Report();
    const size_t controls = std::string(axes).size();
    for (const char* key : {"phi_min", "phi_max", "phi_p1", "phi_p99", "final_phi"}) {
      ASSERT_TRUE(j[key].is_array()) << key;
      EXPECT_EQ(j[key].size(), controls) << axes << " " << key;
      for (const auto& v : j[key]) EXPECT_TRUE(v.is_number()) << axes << " " << key;
    }
    EXPECT_LE(j["phi_min"][0].get<double>(), j["phi_max"][0].get<double>());
  }
}

TEST_F(JsonReportTest, UnsetAndNonFiniteValuesAreNull) {
  scenario_.simulation.lock_threshold_deg = 1e-9;  // never reached: no lock, no window
  const nlohmann::ordered_json j = Report();
  EXPECT_TRUE(j["lock_time_s"].is_null());
  EXPECT_TRUE(j["first_lock_time_s"].is_null());
  EXPECT_TRUE(j["statistics_from_s"].is_null());
  EXPECT_EQ(j["statistics_samples"], 0);
  for (const char* key : {"mean", "p50", "p99", "max"}) {
    EXPECT_TRUE(j["error_deg"][key].is_null()) << key;
  }
  EXPECT_TRUE(j["extinction_db_mean"].is_null());
  EXPECT_TRUE(j["extinction_db_power_mean"].is_null());
  // The controls still moved.
  EXPECT_TRUE(j["phi_min"][0].is_number());
  // Serialized as JSON null, parseable back.
  const nlohmann::json parsed = nlohmann::json::parse(j.dump());
  EXPECT_TRUE(parsed["lock_time_s"].is_null());
  EXPECT_TRUE(parsed["error_deg"]["mean"].is_null());
}

TEST_F(JsonReportTest, NoRotatingDisturbanceGivesANullRate) {
  scenario_.input.disturbances.clear();
  const nlohmann::ordered_json j = Report();
  EXPECT_TRUE(j["rate_rad_per_s"].is_null());
}

TEST_F(JsonReportTest, WarningsArePassedThrough) {
  EXPECT_EQ(Report({"first", "second"})["warnings"],
            nlohmann::ordered_json::array({"first", "second"}));
  const nlohmann::ordered_json none = Report();
  ASSERT_TRUE(none["warnings"].is_array());
  EXPECT_TRUE(none["warnings"].empty());
}

TEST(InputRateRadPerSTest, FirstScramblerOrConstantRotation) {
  ScenarioConfig scenario = PaperScenario("131");
  EXPECT_NEAR(InputRateRadPerS(scenario), 1e5, kTolerance);

  DisturbanceConfig walk;
  walk.kind = DisturbanceConfig::Kind::kRandomWalk;
  walk.rate_rad_per_s = 9.0;  // not a rotation rate for this kind
  DisturbanceConfig rotation;
  rotation.kind = DisturbanceConfig::Kind::kConstantRotation;
  rotation.rate_rad_per_s = 250.0;
  DisturbanceConfig burst;
  burst.kind = DisturbanceConfig::Kind::kTransientBurst;
  burst.rate_rad_per_s = 77.0;
  scenario.input.disturbances = {walk, burst, rotation, DisturbanceConfig{}};
  EXPECT_NEAR(InputRateRadPerS(scenario), 250.0, kTolerance);
}

TEST(InputRateRadPerSTest, NaNWithoutOne) {
  ScenarioConfig scenario = PaperScenario("131");
  scenario.input.disturbances.clear();
  EXPECT_TRUE(std::isnan(InputRateRadPerS(scenario)));
  DisturbanceConfig walk;
  walk.kind = DisturbanceConfig::Kind::kRandomWalk;
  scenario.input.disturbances = {walk};
  EXPECT_TRUE(std::isnan(InputRateRadPerS(scenario)));
}

TEST_F(JsonReportTest, TextNamesScenarioMethodAndLoop) {
  scenario_.name = "text-check";
  ClosedLoopSimulator simulator(scenario_);
  const std::string text = RunReportText(DescribeRun(simulator), simulator.Run());
  EXPECT_NE(text.find("text-check"), std::string::npos) << text;
  EXPECT_NE(text.find("method gp"), std::string::npos) << text;
  EXPECT_NE(text.find("model loop"), std::string::npos) << text;
  EXPECT_NE(text.find("fast loop"), std::string::npos) << text;
  EXPECT_NE(text.find("null-space step"), std::string::npos) << text;
  EXPECT_NE(text.find("10000 samples"), std::string::npos) << text;
  // The paper's ~5° error sits above the 40-dB line: the recovery line gives its longest stretch.
  EXPECT_NE(text.find("at or above 1.146° (40 dB); the longest"), std::string::npos) << text;
}

TEST_F(JsonReportTest, TextNamesTheGeneralLoopAndANeverLockingRun) {
  scenario_.controller.method = ControlMethod::kPseudoInverse;
  scenario_.controller.loop = LoopMode::kMeasured;
  scenario_.controller.step = 0.02;
  scenario_.simulation.lock_threshold_deg = 1e-9;
  ClosedLoopSimulator simulator(scenario_, [](const ControllerConfig& config, const LawTiming& timing, int controls,
                                                    bool point) {
    return MakeControlLaw(config, timing, controls, point);  // a user factory: always the general loop
  });
  ASSERT_FALSE(simulator.uses_fast_path());
  const std::string text = RunReportText(DescribeRun(simulator), simulator.Run());
  EXPECT_NE(text.find("method pinv"), std::string::npos) << text;
  EXPECT_NE(text.find("measured loop"), std::string::npos) << text;
  EXPECT_NE(text.find("general loop"), std::string::npos) << text;
  EXPECT_NE(text.find("lock       never"), std::string::npos) << text;
  EXPECT_NE(text.find("recovery   never at or above 1.146° (40 dB) in the window"), std::string::npos) << text;
  EXPECT_EQ(text.find("null-space step"), std::string::npos) << text;  // pinv has none
}

}  // namespace
}  // namespace dpc::cli
