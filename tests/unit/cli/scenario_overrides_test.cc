#include "dpc/cli/scenario_overrides.h"

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_error.h"

namespace dpc::cli {
namespace {

constexpr double kTolerance = 1e-15;

// Parses real argv (program name + `args`) through a CLI::App carrying the override flags.
class ScenarioOverridesTest : public ::testing::Test {
 protected:
  void SetUp() override { overrides_.AddTo(app_); }

  void Parse(std::vector<std::string> args) {
    args.insert(args.begin(), "dpc");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    app_.parse(static_cast<int>(argv.size()), argv.data());
  }

  // Parses `args` and applies them to `scenario_`; returns the ScenarioError's location, or ""
  // if Apply did not throw.
  std::string ApplyAndGetErrorLocation(const std::vector<std::string>& args) {
    Parse(args);
    try {
      overrides_.Apply(&scenario_);
    } catch (const ScenarioError& e) {
      message_ = e.message();
      return e.location();
    }
    return "";
  }

  static DisturbanceConfig Disturbance(DisturbanceConfig::Kind kind, double rate_rad_per_s) {
    DisturbanceConfig d;
    d.kind = kind;
    d.rate_rad_per_s = rate_rad_per_s;
    return d;
  }

  CLI::App app_{"scenario overrides test"};
  ScenarioOverrides overrides_;
  ScenarioConfig scenario_ = PaperScenario("131");
  std::string message_;
};

TEST_F(ScenarioOverridesTest, NoFlagsLeaveTheScenarioAlone) {
  Parse({});
  overrides_.Apply(&scenario_);
  const ScenarioConfig paper = PaperScenario("131");
  EXPECT_EQ(scenario_.stages.size(), 3u);
  EXPECT_EQ(scenario_.controller.method, paper.controller.method);
  EXPECT_EQ(scenario_.controller.loop, paper.controller.loop);
  EXPECT_EQ(scenario_.controller.step, paper.controller.step);
  EXPECT_EQ(scenario_.simulation.duration_s, paper.simulation.duration_s);
  EXPECT_EQ(scenario_.simulation.seed, paper.simulation.seed);
  EXPECT_FALSE(scenario_.simulation.statistics_start_s.has_value());
  ASSERT_EQ(scenario_.input.disturbances.size(), 1u);
  EXPECT_EQ(scenario_.input.disturbances[0].rate_rad_per_s, 1e5);
  for (const char* path :
       {"stages", "controller.step", "controller.method", "controller.loop", "simulation.seed",
        "input.disturbances[0].paper_scrambler.rate_rad_per_s"}) {
    EXPECT_FALSE(overrides_.FlagForField(path).has_value()) << path;
  }
}

TEST_F(ScenarioOverridesTest, FlagsTheLawDoesNotUseAreNamed) {
  // pinv has no threshold, no null space and no damping: each flag is named once.
  Parse({"--method", "pinv", "--threshold", "0.7", "--nullspace-step", "0.05", "--damping", "0.01"});
  overrides_.Apply(&scenario_);
  const std::vector<std::string> ignored = overrides_.IgnoredFlags(scenario_);
  ASSERT_EQ(ignored.size(), 3u);
  EXPECT_EQ(ignored[0], "--threshold applies to gpt; method pinv ignores it");
  EXPECT_EQ(ignored[1], "--nullspace-step applies to gp, gpt and extended; method pinv ignores it");
  EXPECT_EQ(ignored[2], "--damping applies to damped, rls, gp and gpt; method pinv ignores it");
  // gp uses the null-space step and the damping.
  scenario_.controller.method = ControlMethod::kGradientProjection;
  EXPECT_EQ(overrides_.IgnoredFlags(scenario_).size(), 1u);  // --threshold
}

TEST_F(ScenarioOverridesTest, FlagsTheLawUsesAreNotNamed) {
  Parse({"--method", "gpt", "--threshold", "0.7", "--nullspace-step", "0.05", "--damping", "0.1",
         "--damping-threshold", "0.3"});
  overrides_.Apply(&scenario_);
  EXPECT_TRUE(overrides_.IgnoredFlags(scenario_).empty());
}

TEST_F(ScenarioOverridesTest, EveryFlagSetsItsField) {
  Parse({"--method", "pinv", "--step", "0.3", "--nullspace-step", "0.05", "--threshold", "0.7",
         "--damping", "0.01", "--loop", "measured", "--activation-s", "1e-4", "--duration-s",
         "5e-3", "--delay-s", "2e-7", "--sample-rate-hz", "1e7", "--seed", "18446744073709551615",
         "--noise-deg", "0.5", "--lock-threshold-deg", "3", "--statistics-from-s", "1e-3",
         "--settle-samples", "50", "--rate-rad-per-s", "2e4"});
  overrides_.Apply(&scenario_);
  const ControllerConfig& c = scenario_.controller;
  EXPECT_EQ(c.method, ControlMethod::kPseudoInverse);
  EXPECT_NEAR(c.step, 0.3, kTolerance);
  EXPECT_NEAR(c.nullspace_step, 0.05, kTolerance);
  EXPECT_NEAR(c.threshold, 0.7, kTolerance);
  EXPECT_NEAR(c.damping, 0.01, kTolerance);
  EXPECT_EQ(c.loop, LoopMode::kMeasured);
  EXPECT_NEAR(c.activation_s, 1e-4, kTolerance);
  const SimulationConfig& s = scenario_.simulation;
  EXPECT_NEAR(s.duration_s, 5e-3, kTolerance);
  EXPECT_NEAR(s.delay_s, 2e-7, kTolerance);
  EXPECT_NEAR(s.sample_rate_hz, 1e7, kTolerance);
  EXPECT_EQ(s.seed, UINT64_MAX);
  EXPECT_NEAR(s.polarimeter_noise_deg, 0.5, kTolerance);
  EXPECT_NEAR(s.lock_threshold_deg, 3.0, kTolerance);
  ASSERT_TRUE(s.statistics_start_s.has_value());
  EXPECT_NEAR(*s.statistics_start_s, 1e-3, kTolerance);
  EXPECT_EQ(s.settle_samples, 50);
  ASSERT_EQ(scenario_.input.disturbances.size(), 1u);
  EXPECT_NEAR(scenario_.input.disturbances[0].rate_rad_per_s, 2e4, kTolerance);
  // Untouched: the device.
  EXPECT_EQ(scenario_.stages.size(), 3u);
}

TEST_F(ScenarioOverridesTest, ParseRejectsValuesOfTheWrongType) {
  EXPECT_THROW(Parse({"--step", "fast"}), CLI::ParseError);
}

struct FlagCase {
  std::vector<std::string> args;
  const char* field_path;
  const char* flag;
};

// Each flag alone names its own field, and no other.
TEST(ScenarioOverridesFlagForFieldTest, EachFlagNamesItsFieldOnly) {
  const std::vector<FlagCase> cases{
      {{"--stages-axes", "3131"}, "stages", "--stages-axes"},
      {{"--method", "gpt"}, "controller.method", "--method"},
      {{"--step", "0.2"}, "controller.step", "--step"},
      {{"--nullspace-step", "0.2"}, "controller.nullspace_step", "--nullspace-step"},
      {{"--threshold", "0.2"}, "controller.threshold", "--threshold"},
      {{"--damping", "0.2"}, "controller.singularity_damping.max_damping", "--damping"},
      {{"--damping-threshold", "0.2"}, "controller.singularity_damping.threshold",
       "--damping-threshold"},
      {{"--predict"}, "controller.prediction", "--predict"},
      {{"--predict-window", "300"}, "controller.prediction.window_samples", "--predict-window"},
      {{"--range", "1"}, "stages[1].range", "--range"},
      {{"--target-set", "0,0,1"}, "target.set", "--target-set"},
      {{"--target-point", "0,1,0"}, "target.point", "--target-point"},
      {{"--loop", "measured"}, "controller.loop", "--loop"},
      {{"--activation-s", "1e-4"}, "controller.activation_s", "--activation-s"},
      {{"--rate-rad-per-s", "7"}, "input.disturbances[0].paper_scrambler.rate_rad_per_s",
       "--rate-rad-per-s"},
      {{"--duration-s", "1e-3"}, "simulation.duration_s", "--duration-s"},
      {{"--delay-s", "1e-7"}, "simulation.delay_s", "--delay-s"},
      {{"--sample-rate-hz", "1e7"}, "simulation.sample_rate_hz", "--sample-rate-hz"},
      {{"--seed", "3"}, "simulation.seed", "--seed"},
      {{"--noise-deg", "1"}, "simulation.polarimeter_noise_deg", "--noise-deg"},
      {{"--lock-threshold-deg", "5"}, "simulation.lock_threshold_deg", "--lock-threshold-deg"},
      {{"--statistics-from-s", "1e-3"}, "simulation.statistics_start_s", "--statistics-from-s"},
      {{"--settle-samples", "10"}, "simulation.settle_samples", "--settle-samples"},
  };
  for (const FlagCase& c : cases) {
    CLI::App app;
    ScenarioOverrides overrides;
    overrides.AddTo(app);
    std::vector<std::string> args = c.args;
    args.insert(args.begin(), "dpc");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    app.parse(static_cast<int>(argv.size()), argv.data());
    ScenarioConfig scenario = PaperScenario("131");
    overrides.Apply(&scenario);
    EXPECT_EQ(overrides.FlagForField(c.field_path), std::optional<std::string>(c.flag)) << c.flag;
    for (const FlagCase& other : cases) {
      // A field inside another (stages[1].range in stages) belongs to both flags' reach.
      const std::string mine = c.field_path, theirs = other.field_path;
      const auto inside = [](const std::string& inner, const std::string& outer) {
        return inner == outer || inner.rfind(outer + ".", 0) == 0 ||
               inner.rfind(outer + "[", 0) == 0;
      };
      if (inside(mine, theirs) || inside(theirs, mine)) continue;
      EXPECT_EQ(overrides.FlagForField(other.field_path), std::nullopt)
          << c.flag << " claims " << other.field_path;
    }
  }
}

TEST_F(ScenarioOverridesTest, DampingSetsLambdaForRls) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--method", "rls", "--damping", "0.2"}), "");
  EXPECT_EQ(scenario_.controller.damping, 0.2);
  EXPECT_FALSE(scenario_.controller.singularity_damping.has_value());
  EXPECT_EQ(overrides_.FlagForField("controller.damping"), "--damping");
}

TEST_F(ScenarioOverridesTest, DampingTurnsOnSingularityDampingForGradientProjection) {
  EXPECT_EQ(ApplyAndGetErrorLocation(
                {"--method", "gpt", "--damping", "0.3", "--damping-threshold", "0.7"}),
            "");
  ASSERT_TRUE(scenario_.controller.singularity_damping.has_value());
  EXPECT_EQ(scenario_.controller.singularity_damping->max_damping, 0.3);
  EXPECT_EQ(scenario_.controller.singularity_damping->threshold, 0.7);
  EXPECT_EQ(scenario_.controller.damping, 1e-3);
}

TEST_F(ScenarioOverridesTest, RangePredictAndTargetSet) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--range", "1", "--predict", "--target-set", "0,0,1"}), "");
  for (const StageConfig& stage : scenario_.stages) {
    ASSERT_TRUE(stage.range.has_value());
    EXPECT_EQ(stage.range->min, -1.0);
    EXPECT_EQ(stage.range->max, 1.0);
  }
  EXPECT_EQ(scenario_.controller.nullspace_criterion, NullspaceCriterion::kRange);
  ASSERT_TRUE(scenario_.controller.prediction.has_value());
  EXPECT_EQ(scenario_.controller.prediction->window_samples, 1000.0);
  EXPECT_EQ(scenario_.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(scenario_.target.normal, Vector3::UnitZ());
  EXPECT_EQ(scenario_.target.offset, 0.0);
}

TEST_F(ScenarioOverridesTest, PredictContradictsNoPredict) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--predict", "--no-predict"}), "--predict");
}

TEST_F(ScenarioOverridesTest, TargetLinearIsTheSetS3EqualsZero) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--target-linear"}), "");
  EXPECT_EQ(scenario_.target.kind, TargetConfig::Kind::kSet);
  EXPECT_EQ(scenario_.target.normal, Vector3::UnitZ());
  EXPECT_EQ(scenario_.target.offset, 0.0);
}

TEST_F(ScenarioOverridesTest, OneTargetOnly) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--target-set", "0,0,1", "--target-point", "0,1,0"}),
            "--target-point");
}

TEST_F(ScenarioOverridesTest, FlagForFieldCoversPathsInsideTheField) {
  Parse({"--stages-axes", "131", "--step", "0.2"});
  overrides_.Apply(&scenario_);
  EXPECT_EQ(overrides_.FlagForField("stages[2].axis_vector"), "--stages-axes");
  EXPECT_EQ(overrides_.FlagForField("stages[0].map.table.angle_rad[3]"), "--stages-axes");
  EXPECT_EQ(overrides_.FlagForField("controller.step"), "--step");
  EXPECT_EQ(overrides_.FlagForField("controller.step.inner"), "--step");
}

TEST_F(ScenarioOverridesTest, FlagForFieldMatchesWholeFieldNamesOnly) {
  Parse({"--step", "0.2", "--stages-axes", "131"});
  overrides_.Apply(&scenario_);
  EXPECT_EQ(overrides_.FlagForField("controller.steps"), std::nullopt);
  EXPECT_EQ(overrides_.FlagForField("controller.nullspace_step"), std::nullopt);
  EXPECT_EQ(overrides_.FlagForField("controller"), std::nullopt);
  EXPECT_EQ(overrides_.FlagForField("stages_extra"), std::nullopt);
  EXPECT_EQ(overrides_.FlagForField(""), std::nullopt);
}

TEST_F(ScenarioOverridesTest, FlagForFieldIsEmptyBeforeApply) {
  Parse({"--step", "0.2"});
  EXPECT_EQ(overrides_.FlagForField("controller.step"), std::nullopt);
}

TEST_F(ScenarioOverridesTest, StagesAxesReplacesTheStagesAndClearsInitialPhi) {
  scenario_.controller.initial_phi = {0.1, 0.2, 0.3};
  Parse({"--stages-axes", "3132"});
  overrides_.Apply(&scenario_);
  ASSERT_EQ(scenario_.stages.size(), 4u);
  const Vector3 expected_axes[] = {Vector3::UnitZ(), Vector3::UnitX(), Vector3::UnitZ(),
                                   Vector3::UnitY()};
  for (int i = 0; i < 4; ++i) {
    const StageConfig& stage = scenario_.stages[i];
    EXPECT_EQ(stage.kind, StageConfig::Kind::kFixedAxis) << i;
    EXPECT_NEAR((stage.axis - expected_axes[i]).norm(), 0.0, kTolerance) << i;
    EXPECT_EQ(stage.map.kind, ControlMapConfig::Kind::kLinear) << i;
    EXPECT_NEAR(stage.map.rad_per_unit, M_PI, kTolerance) << i;
    EXPECT_NEAR(stage.map.offset_rad, 0.0, kTolerance) << i;
    EXPECT_FALSE(stage.range.has_value()) << i;
  }
  EXPECT_TRUE(scenario_.controller.initial_phi.empty());
}

TEST_F(ScenarioOverridesTest, BadStagesAxesThrowNamingTheFlag) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--stages-axes", "14"}), "--stages-axes");
  EXPECT_NE(message_.find("'4'"), std::string::npos) << message_;
}

TEST_F(ScenarioOverridesTest, UnknownMethodThrowsNamingTheFlag) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--method", "newton"}), "--method");
  EXPECT_NE(message_.find("\"newton\""), std::string::npos) << message_;
  EXPECT_NE(message_.find("gp"), std::string::npos) << message_;  // lists the known ones
}

TEST_F(ScenarioOverridesTest, UnknownLoopThrowsNamingTheFlag) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--loop", "open"}), "--loop");
  EXPECT_NE(message_.find("\"open\""), std::string::npos) << message_;
}

TEST_F(ScenarioOverridesTest, LoopModelSetsModel) {
  scenario_.controller.loop = LoopMode::kMeasured;
  Parse({"--loop", "model"});
  overrides_.Apply(&scenario_);
  EXPECT_EQ(scenario_.controller.loop, LoopMode::kModel);
}

TEST_F(ScenarioOverridesTest, StaticWithARateThrows) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--static", "--rate-rad-per-s", "5"}), "--static");
  EXPECT_NE(message_.find("--rate-rad-per-s"), std::string::npos) << message_;
}

TEST_F(ScenarioOverridesTest, StaticRemovesEveryDisturbance) {
  scenario_.input.disturbances.push_back(
      Disturbance(DisturbanceConfig::Kind::kRandomWalk, 0.0));
  Parse({"--static"});
  overrides_.Apply(&scenario_);
  EXPECT_TRUE(scenario_.input.disturbances.empty());
}

TEST_F(ScenarioOverridesTest, RateUpdatesEveryScramblerAndConstantRotationOnly) {
  scenario_.input.disturbances = {
      Disturbance(DisturbanceConfig::Kind::kPaperScrambler, 1e5),
      Disturbance(DisturbanceConfig::Kind::kRandomWalk, 11.0),
      Disturbance(DisturbanceConfig::Kind::kConstantRotation, 3.0),
      Disturbance(DisturbanceConfig::Kind::kTransientBurst, 7.0),
      Disturbance(DisturbanceConfig::Kind::kPaperScrambler, 5.0),
  };
  Parse({"--rate-rad-per-s", "2e4"});
  overrides_.Apply(&scenario_);
  const auto& d = scenario_.input.disturbances;
  ASSERT_EQ(d.size(), 5u);  // nothing added
  EXPECT_NEAR(d[0].rate_rad_per_s, 2e4, kTolerance);
  EXPECT_NEAR(d[1].rate_rad_per_s, 11.0, kTolerance);
  EXPECT_NEAR(d[2].rate_rad_per_s, 2e4, kTolerance);
  EXPECT_NEAR(d[3].rate_rad_per_s, 7.0, kTolerance);
  EXPECT_NEAR(d[4].rate_rad_per_s, 2e4, kTolerance);
  const std::optional<std::string> flag = "--rate-rad-per-s";
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[0].paper_scrambler.rate_rad_per_s"), flag);
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[2].constant_rotation.rate_rad_per_s"),
            flag);
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[4].paper_scrambler.rate_rad_per_s"), flag);
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[1].random_walk.diffusion_rad_per_sqrt_s"),
            std::nullopt);
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[3].transient_burst.rate_rad_per_s"),
            std::nullopt);
  // Only the rate: the scrambler's other fields are the file's.
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[0].paper_scrambler.kick_rms_ratio"),
            std::nullopt);
}

TEST_F(ScenarioOverridesTest, RateAddsAPaperScramblerWhenThereIsNone) {
  scenario_.input.disturbances = {Disturbance(DisturbanceConfig::Kind::kRandomWalk, 0.0)};
  Parse({"--rate-rad-per-s", "300"});
  overrides_.Apply(&scenario_);
  const auto& d = scenario_.input.disturbances;
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].kind, DisturbanceConfig::Kind::kRandomWalk);
  EXPECT_EQ(d[1].kind, DisturbanceConfig::Kind::kPaperScrambler);
  EXPECT_NEAR(d[1].rate_rad_per_s, 300.0, kTolerance);
  const DisturbanceConfig defaults;
  EXPECT_NEAR((d[1].axis - defaults.axis).norm(), 0.0, kTolerance);
  EXPECT_NEAR(d[1].kick_rms_ratio, defaults.kick_rms_ratio, kTolerance);
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[1].paper_scrambler.rate_rad_per_s"),
            "--rate-rad-per-s");
  EXPECT_EQ(overrides_.FlagForField("input.disturbances[0].random_walk.diffusion_rad_per_sqrt_s"),
            std::nullopt);
}

TEST_F(ScenarioOverridesTest, RateGivesAStaticInputAScrambler) {
  scenario_.input.disturbances.clear();
  Parse({"--rate-rad-per-s", "300"});
  overrides_.Apply(&scenario_);
  ASSERT_EQ(scenario_.input.disturbances.size(), 1u);
  EXPECT_EQ(scenario_.input.disturbances[0].kind, DisturbanceConfig::Kind::kPaperScrambler);
  EXPECT_NEAR(scenario_.input.disturbances[0].rate_rad_per_s, 300.0, kTolerance);
}

TEST_F(ScenarioOverridesTest, OperatingTemperatureSetsEveryMapKeyedByTemperature) {
  ControlMapConfig keyed;
  keyed.kind = ControlMapConfig::Kind::kTablesByCondition;
  keyed.operating_point = 20.0;
  keyed.condition_tables = {{20.0, {0, 1}, {0, 1}}, {40.0, {0, 1}, {0, 1.1}}};
  scenario_.stages[0].map = keyed;
  scenario_.stages[2].map = keyed;
  EXPECT_EQ(ApplyAndGetErrorLocation({"--operating-temperature-c", "32.5"}), "");
  EXPECT_EQ(scenario_.stages[0].map.operating_point, 32.5);
  EXPECT_EQ(scenario_.stages[1].map.kind, ControlMapConfig::Kind::kLinear);
  EXPECT_EQ(scenario_.stages[2].map.operating_point, 32.5);
  EXPECT_EQ(overrides_.FlagForField("stages[2].map.tables_by_condition.operating_temperature_c"),
            "--operating-temperature-c");
}

TEST_F(ScenarioOverridesTest, AnOperatingPointWithoutAMapKeyedByItThrowsNamingTheFlag) {
  EXPECT_EQ(ApplyAndGetErrorLocation({"--operating-wavelength-nm", "1550"}), "--operating-wavelength-nm");
  EXPECT_NE(message_.find("no map of the scenario is keyed by wavelength"), std::string::npos) << message_;
}

TEST_F(ScenarioOverridesTest, ApplyingAgainGivesTheSameResult) {
  Parse({"--rate-rad-per-s", "300", "--step", "0.4"});
  overrides_.Apply(&scenario_);
  ScenarioConfig second = PaperScenario("3131");
  overrides_.Apply(&second);
  EXPECT_EQ(second.stages.size(), 4u);
  EXPECT_NEAR(second.controller.step, 0.4, kTolerance);
  ASSERT_EQ(second.input.disturbances.size(), 1u);
  EXPECT_NEAR(second.input.disturbances[0].rate_rad_per_s, 300.0, kTolerance);
  EXPECT_EQ(overrides_.FlagForField("controller.step"), "--step");
}

}  // namespace
}  // namespace dpc::cli
