#include "driver_core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

#include "dpc/config/scenario_config.h"
#include "driver_core_support.h"

namespace dpc::services {
namespace {

using namespace dpc::services::testing;

TEST_F(DriverCoreTest, StartsHoldingWithTheBackendsPhi) {
  const DriverState state = core_.State(0);
  EXPECT_EQ(state.mode, DriverMode::kHolding);
  EXPECT_EQ(Phi(state), std::vector<double>({0.0, 0.0, 0.0}));
  EXPECT_NE(state.reason.find("no controller"), std::string::npos);
  // Published states are numbered from 1; State() only looks.
  EXPECT_EQ(state.sequence, 0u);
  EXPECT_EQ(core_.Publishable(0).sequence, 1u);
  EXPECT_EQ(core_.Publishable(0).sequence, 2u);
}

TEST_F(DriverCoreTest, AppliesTheFirstControllersCommandAndAnswersItsSample) {
  auto state = Send(core_, Command("A", 0, {0.1, 0.2, 0.3}, 7), 1 * kMs, 5);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kActive);
  EXPECT_EQ(state->obeyed_controller_id, "A");
  EXPECT_EQ(state->answers_sample, 7u);
  EXPECT_EQ(Phi(*state), std::vector<double>({0.1, 0.2, 0.3}));
  EXPECT_EQ(backend_.Applied().phi, (ControlVector(3) << 0.1, 0.2, 0.3).finished());
}

TEST_F(DriverCoreTest, AnswersTheObeyedControllersMalformedCommandWithoutApplyingIt) {
  // (What makes a command malformed is bus::ReadCommand's business: tested with the bus.)
  ASSERT_TRUE(Send(core_, Command("A", 0, {0.1, 0.2, 0.3}, 1), 1 * kMs, 0));
  core_.OnSample(2, 0, 0);
  auto state = core_.OnMalformedCommand("A", 2, "phi[0] = nan is not finite", 0);
  ASSERT_TRUE(state.has_value()) << "the obeyed controller's bad command is answered";
  EXPECT_EQ(state->answers_sample, 2u);
  EXPECT_EQ(Phi(*state), std::vector<double>({0.1, 0.2, 0.3}));
  EXPECT_EQ(core_.commands_rejected(), 1u);
  EXPECT_EQ(core_.last_rejection(), "from A: phi[0] = nan is not finite");
  // Not when it names a sample the bench never published, nor for a stranger.
  EXPECT_FALSE(core_.OnMalformedCommand("A", 1000, "oversized", 0));
  EXPECT_FALSE(core_.OnMalformedCommand("B", 2, "oversized", 0));
  EXPECT_EQ(core_.commands_rejected(), 3u);
  EXPECT_EQ(core_.obeyed(), "A");
  EXPECT_EQ(backend_.Applied().phi, Controls({0.1, 0.2, 0.3}));
}

TEST(DriverCoreLimits, ClampsToTheStageRangeAndReportsSaturation) {
  std::vector<StageConfig> stages = StagesFromAxes("131");
  stages[1].range = ControlRange{-0.5, 0.5};
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(stages, DriverSettings{}, &backend);
  auto state = Send(core, Command("A", 0, {0.1, 0.9, -0.2}, 1), 0, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(Phi(*state), std::vector<double>({0.1, 0.5, -0.2}));
  EXPECT_EQ(Saturated(*state), std::vector<bool>({false, true, false}));
  EXPECT_EQ(state->commands_limited, 1u);
}

TEST(DriverCoreLimits, LimitsTheSlewOverTheDriversTime) {
  DriverSettings settings;
  settings.max_slew_per_s = 100.0;  // 0.01 per 100 µs
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(StagesFromAxes("131"), settings, &backend);
  ASSERT_TRUE(Send(core, Command("A", 0, {0.0, 0.0, 0.0}, 1, 0), 0, 0));
  auto state = Send(core, Command("A", 0, {0.5, -0.005, 0.0}, 2, 100 * kUs), 100 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(Phi(*state)[0], 0.01, 1e-12);
  EXPECT_NEAR(Phi(*state)[1], -0.005, 1e-12);
  EXPECT_EQ(Saturated(*state), std::vector<bool>({true, false, false}));
}


ControllerCommand RampCommand(std::vector<double> phi, std::vector<double> rate, uint64_t sample,
                              int64_t sample_time_ns) {
  ControllerCommand c = Command("A", 0, std::move(phi), sample, sample_time_ns);
  c.rate_per_s = Controls(rate);
  return c;
}

ControlVector At(const DriverState& state, int64_t t_ns) {
  ControlVector phi;
  state.motion.At(t_ns, &phi);
  return phi;
}

TEST_F(DriverCoreTest, ARatedCommandMovesTheWaveplatesFromItsSampleTimeForAtMostTheRampLimit) {
  // Sample at bench time 10 ms; the command arrives whenever it arrives.
  auto state = Send(core_, RampCommand({0.1, 0.2, 0.3}, {10.0, 0.0, -5.0}, 1, 10 * kMs), 50 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(Phi(*state), std::vector<double>({0.1, 0.2, 0.3}));
  EXPECT_EQ(Rates(*state), std::vector<double>({10.0, 0.0, -5.0}));
  EXPECT_EQ(state->motion.start_ns, 10 * kMs);
  EXPECT_EQ(RampEnd(*state), 12 * kMs);  // DriverSettings::max_ramp_s = 2 ms
  EXPECT_EQ(Saturated(*state), std::vector<bool>({false, false, false}));
  // 300 µs after the sample: 0.1 + 10 × 3e-4.
  EXPECT_NEAR(At(*state, 10 * kMs + 300 * kUs)[0], 0.103, 1e-12);
  EXPECT_NEAR(At(*state, 10 * kMs + 300 * kUs)[2], 0.2985, 1e-12);
  // Before its start the motion has not begun; after its end it stops.
  EXPECT_NEAR(At(*state, 0)[0], 0.1, 1e-12);
  EXPECT_NEAR(At(*state, 1000 * kMs)[0], 0.12, 1e-12);
}

TEST_F(DriverCoreTest, HoldingStopsTheMotionWhereItEnds) {
  ASSERT_TRUE(Send(core_, RampCommand({0.1, 0.2, 0.3}, {10.0, 0.0, -5.0}, 1, 0), 0, 0));
  auto state = core_.Tick(3 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_TRUE(Rates(*state).empty());
  ASSERT_EQ(Phi(*state).size(), 3u);
  EXPECT_NEAR(Phi(*state)[0], 0.12, 1e-12);   // where the 2-ms ramp ended
  EXPECT_NEAR(Phi(*state)[2], 0.29, 1e-12);
  EXPECT_NEAR(backend_.Applied().phi[0], 0.12, 1e-12);
  EXPECT_FALSE(backend_.Applied().moving);
}

TEST_F(DriverCoreTest, TheNextCommandStartsFromWhereTheRampHasTheWaveplates) {
  DriverSettings settings;
  settings.max_slew_per_s = 20.0;  // 0.002 per 100 µs
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(StagesFromAxes("131"), settings, &backend);
  ASSERT_TRUE(Send(core, RampCommand({0.0, 0.0, 0.0}, {15.0, 0.0, 0.0}, 1, 0), 0, 0));
  // 100 µs later the ramp has φ0 at 0.0015; a command for 0.004 may step 0.002 from there.
  auto state = Send(core, RampCommand({0.004, 0.0, 0.0}, {15.0, 0.0, 0.0}, 2, 100 * kUs), 100 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(Phi(*state)[0], 0.0035, 1e-12);
  EXPECT_EQ(Saturated(*state), std::vector<bool>({true, false, false}));
  // A rate above the slew limit is cut to it.
  state = Send(core, RampCommand({0.0035, 0.0, 0.0}, {50.0, -50.0, 1.0}, 3, 200 * kUs), 200 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(Rates(*state), std::vector<double>({20.0, -20.0, 1.0}));
  EXPECT_EQ(Saturated(*state), std::vector<bool>({true, true, false}));
}

TEST(DriverCoreLimits, TheSlewBudgetIsTheDriversOwnTimeNotTheCommandsTimestamps) {
  DriverSettings settings;
  settings.max_slew_per_s = 20.0;  // 0.002 per 100 µs of the driver's clock
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(StagesFromAxes("131"), settings, &backend);
  ASSERT_TRUE(Send(core, Command("A", 0, {0.0, 0.0, 0.0}, 1, 0), 0, 0));
  // The bench's sample 2 is at 100 µs; a command claiming 4e18 ns (127 years) for it is refused.
  core.OnSample(2, 100 * kUs, 0);
  EXPECT_FALSE(core.OnCommand(Command("A", 0, {0.906, 0.0, 0.0}, 2, 4'000'000'000'000'000'000), 100 * kUs, 0));
  EXPECT_NE(core.last_rejection().find("is not the time of sample 2"), std::string::npos) << core.last_rejection();
  // A command that tells the truth but arrives 100 µs after the last one steps 0.002.
  auto state = core.OnCommand(Command("A", 0, {0.906, 0.0, 0.0}, 2, 100 * kUs), 100 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(Phi(*state)[0], 0.002, 1e-12);
  EXPECT_EQ(Saturated(*state), std::vector<bool>({true, false, false}));
  // One that arrives at the same instant of the driver's clock does not move at all.
  state = core.OnCommand(Command("A", 0, {0.906, 0.0, 0.0}, 2, 100 * kUs), 100 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(Phi(*state)[0], 0.002, 1e-12);
}

TEST_F(DriverCoreTest, ACommandIsJudgedByTheBenchsRecordOfItsSample) {
  core_.OnSample(1, 0, 11);
  core_.OnSample(2, 100 * kUs, 22);
  // Answering a sample the bench never published, far ahead of its newest: refused, unanswered.
  EXPECT_FALSE(core_.OnCommand(Command("A", 0, {0.1, 0.1, 0.1}, 1000), 1 * kMs, 0));
  EXPECT_NE(core_.last_rejection().find("the bench's newest sample is 2"), std::string::npos)
      << core_.last_rejection();
  EXPECT_FALSE(core_.OnCommand(Command("A", 0, {0.1, 0.1, 0.1}, 0), 1 * kMs, 0));
  EXPECT_EQ(core_.commands_rejected(), 2u);
  EXPECT_TRUE(core_.holding());
  // A recorded sample's times in the state are the bench's, not the command's.
  ControllerCommand recorded = Command("A", 0, {0.1, 0.1, 0.1}, 2, 100 * kUs);
  recorded.sample_publish_time_ns = -5;
  auto state = core_.OnCommand(recorded, 1 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->sample_publish_time_ns, 22);
  // A sample still on its way (one past the newest) is fine; its motion starts at the time the
  // bench's period puts it at (200 µs), whatever the command says.
  ControllerCommand ahead = Command("A", 0, {0.1, 0.1, 0.1}, 3, 99 * kMs);
  ahead.rate_per_s = Controls({1.0, 0.0, 0.0});
  state = core_.OnCommand(ahead, 2 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->motion.start_ns, 200 * kUs);
  EXPECT_EQ(state->sample_time_ns, 200 * kUs);
  // An answer to a sample older than one already answered would move the waveplates back in
  // bench time: not applied.
  EXPECT_FALSE(core_.OnCommand(Command("A", 0, {0.2, 0.1, 0.1}, 2), 3 * kMs, 0));
  EXPECT_EQ(core_.State(0).answers_sample, 3u);
}

TEST(DriverCoreLimits, EveryCommandMeetsTheDevicesOwnFiniteLimits) {
  // No range in the scenario and no --max-slew-per-s: the device's own limits still hold.
  SimulatedWaveplates backend(ControlVector::Zero(3), DeviceLimits{2.0, 50.0});
  DriverCore core(StagesFromAxes("131"), DriverSettings{}, &backend);
  EXPECT_EQ(core.max_slew_per_s(), 50.0);
  auto state = Send(core, RampCommand({1e6, -1e6, 0.5}, {1e300, -1e300, 1.0}, 1, 0), 0, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(Phi(*state), std::vector<double>({2.0, -2.0, 0.5}));
  // At its range ends, the stages pushing outwards get no rate; the third is cut to the slew.
  EXPECT_EQ(Rates(*state), std::vector<double>({0.0, 0.0, 1.0}));
  EXPECT_EQ(Saturated(*state), std::vector<bool>({true, true, false}));
  for (int64_t t : {0L, 1'000'000'000L, std::numeric_limits<int64_t>::max()}) {
    const ControlVector phi = At(*state, t);
    EXPECT_LE(phi.cwiseAbs().maxCoeff(), 2.0) << t;
  }
  // A setting above the device's limit is cut to it; one below narrows it.
  DriverSettings wide;
  wide.max_slew_per_s = 1e9;
  EXPECT_EQ(DriverCore(StagesFromAxes("131"), wide, &backend).max_slew_per_s(), 50.0);
  DriverSettings narrow;
  narrow.max_slew_per_s = 5.0;
  EXPECT_EQ(DriverCore(StagesFromAxes("131"), narrow, &backend).max_slew_per_s(), 5.0);
  // A device without finite limits is refused.
  SimulatedWaveplates unbounded(ControlVector::Zero(3), DeviceLimits{INFINITY, 1.0});
  EXPECT_THROW(DriverCore(StagesFromAxes("131"), DriverSettings{}, &unbounded), std::invalid_argument);
}

TEST(DriverCoreLimits, ARampNearTheEndOfTimeNeitherOverflowsNorRunsForever) {
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(StagesFromAxes("131"), DriverSettings{}, &backend);
  const int64_t late = std::numeric_limits<int64_t>::max() - 1000;
  auto state = Send(core, RampCommand({0.1, 0.0, 0.0}, {1e-300, 0.0, 0.0}, 1, late), 0, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_GE(RampEnd(*state), state->motion.start_ns);
  EXPECT_NEAR(At(*state, std::numeric_limits<int64_t>::max())[0], 0.1, 1e-12);
}

TEST_F(DriverCoreTest, ACommandAnsweringTheLastSampleNumberLeavesTheDriverResponsive) {
  // 2^64 − 1: the driver once looped forever on it, holding its lock.
  ASSERT_TRUE(Send(core_, Command("A", 0, {0.1, 0.1, 0.1}, 1), 0, 0));
  EXPECT_FALSE(core_.OnCommand(Command("B", 0, {0.2, 0.2, 0.2}, std::numeric_limits<uint64_t>::max()),
                               100 * kUs, 0));
  // States keep coming; nobody is made to look behind.
  auto state = Send(core_, Command("A", 0, {0.3, 0.3, 0.3}, 2), 200 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->answers_sample, 2u);
  EXPECT_EQ(core_.obeyed(), "A");
  // Even when the bench itself publishes that number: bounded work, and the next run from 1.
  core_.OnSample(std::numeric_limits<uint64_t>::max(), 300 * kUs, 0);
  ASSERT_TRUE(core_.OnCommand(Command("A", 0, {0.3, 0.3, 0.3}, std::numeric_limits<uint64_t>::max(), 300 * kUs),
                              300 * kUs, 0));
  EXPECT_TRUE(core_.OnSample(1, 0, 0));
  ASSERT_TRUE(Send(core_, Command("A", 0, {0.3, 0.3, 0.3}, 2), 400 * kUs, 0));
  EXPECT_TRUE(core_.Tick(5 * kMs, 0).has_value());
}

TEST(DriverCoreLimits, ARampStopsAtTheFirstRangeEnd) {
  std::vector<StageConfig> stages = StagesFromAxes("131");
  stages[0].range = ControlRange{-0.5, 0.5};
  stages[1].range = ControlRange{-0.5, 0.5};
  SimulatedWaveplates backend(ControlVector::Zero(3));
  DriverCore core(stages, DriverSettings{}, &backend);
  // Stage 0 reaches 0.5 after 1 ms at 100/s; stage 1 is at its end and pushes out: no rate.
  auto state = Send(core, RampCommand({0.4, 0.5, 0.0}, {100.0, 3.0, 7.0}, 1, 0), 0, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(Rates(*state), std::vector<double>({100.0, 0.0, 7.0}));
  EXPECT_NEAR(RampEnd(*state), 1 * kMs, 1);  // rounded down: never past the end
  EXPECT_EQ(Saturated(*state), std::vector<bool>({false, true, false}));
  const ControlVector later = At(*state, 5 * kMs);
  EXPECT_LE(later[0], 0.5);
  EXPECT_NEAR(later[0], 0.5, 1e-6);
  EXPECT_NEAR(later[1], 0.5, 1e-12);
  EXPECT_NEAR(later[2], 0.007, 1e-6);
}

}  // namespace
}  // namespace dpc::services
