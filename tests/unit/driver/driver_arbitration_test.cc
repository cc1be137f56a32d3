#include <fmt/format.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "driver_core.h"
#include "driver_core_support.h"

namespace dpc::services {
namespace {

using namespace dpc::services::testing;

TEST_F(DriverCoreTest, HigherPriorityTakesOverLowerIsIgnored) {
  ASSERT_TRUE(Send(core_, Command("low", 0, {0.1, 0.1, 0.1}, 1), 1 * kMs, 0));
  auto state = Send(core_, Command("high", 5, {0.2, 0.2, 0.2}, 1), 1 * kMs + 10 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->obeyed_controller_id, "high");
  EXPECT_EQ(state->controller_switches, 2u);
  EXPECT_FALSE(Send(core_, Command("low", 0, {0.9, 0.9, 0.9}, 2), 1 * kMs + 100 * kUs, 0));
  EXPECT_EQ(backend_.Applied().phi, ControlVector::Constant(3, 0.2));
}

// Primary and standby answer samples 1 … 50 at 10 kHz (t = 0 … 4.9 ms), then the primary dies.
// Returns the time of the last sample.
int64_t TwoControllersAnswer(DriverCore* core, int first, int last) {
  int64_t t = 0;
  for (int k = first; k <= last; ++k) {
    t = (k - 1) * 100 * kUs;
    Send(*core, Command("primary", 10, {0.1, 0.1, 0.1}, k), t, 0);
    Send(*core, Command("standby", 0, {0.1, 0.1, 0.1}, k), t + 10 * kUs, 0);
  }
  return t;
}

// The standby goes on at 10 kHz after the primary's last command at 4.9 ms; Tick every 25 µs.
// Returns when and by which state the driver switched (-1 if it did not by sample 100).
int64_t FailoverTime(DriverCore* core, std::optional<DriverState>* switch_state) {
  for (int k = 51; k <= 100; ++k) {
    const int64_t t = (k - 1) * 100 * kUs;
    for (int64_t tick = t; tick < t + 100 * kUs; tick += 25 * kUs) {
      auto state = tick == t + 25 * kUs ? Send(*core, Command("standby", 0, {0.1, 0.1, 0.1}, k), tick, 0)
                                        : core->Tick(tick, 0);
      if (core->obeyed() == "standby") {
        *switch_state = state;
        return tick;
      }
    }
  }
  return -1;
}

TEST_F(DriverCoreTest, AFailoverIsPublishedAsAStateNamingTheNewController) {
  const int64_t last_primary = TwoControllersAnswer(&core_, 1, 50);
  ASSERT_EQ(core_.obeyed(), "primary");
  std::optional<DriverState> state;
  const int64_t switched_at = FailoverTime(&core_, &state);
  // The grace (1.2 ms) after the standby answered sample 51, the first the primary did not;
  // seen by the next Tick or standby command.
  ASSERT_GT(switched_at, 0);
  EXPECT_GE(switched_at - last_primary, 1325 * kUs);
  EXPECT_LE(switched_at - last_primary, 1350 * kUs);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(core_.obeyed(), "standby");
  EXPECT_NE(state->reason.find("primary silent for 1.32"), std::string::npos)
      << state->reason;
  EXPECT_NE(state->reason.find("samples behind"), std::string::npos) << state->reason;
}



TEST_F(DriverCoreTest, AStallOfEveryoneHoldsThenGivesControlBackToTheSameController) {
  // No samples for 5 ms (a stalled polarimeter, or the whole machine): nobody answers, so the
  // silence is nobody's failure. On resumption the standby's command happens to come first.
  const int64_t t = TwoControllersAnswer(&core_, 1, 50);
  const uint64_t switches = core_.State(0).controller_switches;
  auto state = core_.Tick(t + 3 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_NE(state->reason.find("primary silent"), std::string::npos) << state->reason;
  state = Send(core_, Command("standby", 0, {0.7, 0.7, 0.7}, 51), t + 5 * kMs, 0);
  ASSERT_TRUE(state.has_value());  // answered (a lockstep bench waits for it), nothing applied
  EXPECT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_EQ(state->answers_sample, 51u);
  EXPECT_EQ(Phi(*state), std::vector<double>({0.1, 0.1, 0.1}));
  state = Send(core_, Command("primary", 10, {0.2, 0.2, 0.2}, 51), t + 5 * kMs + 10 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(core_.obeyed(), "primary");
  EXPECT_EQ(Phi(*state), std::vector<double>({0.2, 0.2, 0.2}));
  // One switch: holding → primary again; the standby was never obeyed.
  EXPECT_EQ(state->controller_switches, switches + 1);
}

TEST_F(DriverCoreTest, ARestartedBenchNumbersItsSamplesFromOneAndNobodyIsBehind) {
  TwoControllersAnswer(&core_, 1, 50);
  // A new polarimeter run: samples 1, 2, 3 … again, the standby's answer first each time.
  for (int k = 1; k <= 30; ++k) {
    const int64_t t = 5 * kMs + k * 100 * kUs;
    EXPECT_EQ(core_.OnSample(k, 0, 0), k == 1) << "sample 1 again is a new bench run";
    EXPECT_FALSE(Send(core_, Command("standby", 0, {0.1, 0.1, 0.1}, k), t, 0).has_value());
    EXPECT_TRUE(Send(core_, Command("primary", 10, {0.1, 0.1, 0.1}, k), t + 10 * kUs, 0).has_value());
    EXPECT_FALSE(core_.Tick(t + 50 * kUs, 0).has_value());
    ASSERT_EQ(core_.obeyed(), "primary") << "sample " << k;
  }
}

TEST_F(DriverCoreTest, HoldsAndSaysWhyWhenNoControllerIsLeftThenResumes) {
  ASSERT_TRUE(Send(core_, Command("only", 0, {0.3, 0.2, 0.1}, 1), 0, 0));
  EXPECT_FALSE(core_.Tick(1 * kMs, 0).has_value());
  auto state = core_.Tick(3 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_NE(state->reason.find("only silent"), std::string::npos) << state->reason;
  EXPECT_EQ(Phi(*state), std::vector<double>({0.3, 0.2, 0.1}));
  // Heartbeats while holding, every 5 ms.
  EXPECT_TRUE(core_.Tick(9 * kMs, 0).has_value());
  EXPECT_FALSE(core_.Tick(10 * kMs, 0).has_value());
  // Another controller starts at 10 kHz. The driver keeps holding, answering its samples,
  // while "only" might still resume (after a stall, whoever's queued command comes first);
  // once "next" has answered samples "only" did not for the grace (1.2 ms), "next" is obeyed.
  int64_t obeyed_at = -1;
  for (int k = 2; k <= 50 && obeyed_at < 0; ++k) {
    const int64_t t = 20 * kMs + (k - 2) * 100 * kUs;
    state = Send(core_, Command("next", 0, {0.31, 0.2, 0.1}, k), t, 0);
    ASSERT_TRUE(state.has_value());
    EXPECT_EQ(state->answers_sample, static_cast<uint64_t>(k));
    if (state->mode == DriverMode::kActive) {
      obeyed_at = t;
      EXPECT_EQ(state->obeyed_controller_id, "next");
      EXPECT_EQ(Phi(*state), std::vector<double>({0.31, 0.2, 0.1}));
    } else {
      EXPECT_EQ(Phi(*state), std::vector<double>({0.3, 0.2, 0.1}));
    }
  }
  EXPECT_GE(obeyed_at - 20 * kMs, 1200 * kUs);
  EXPECT_LE(obeyed_at - 20 * kMs, 1300 * kUs);
}

TEST_F(DriverCoreTest, HoldingSaysSoWhenTheLastControllerLeftTheBus) {
  core_.SetControllersConnected(1);
  ASSERT_TRUE(Send(core_, Command("only", 0, {0.3, 0.2, 0.1}, 1), 0, 0));
  auto state = core_.Tick(3 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  ASSERT_EQ(state->mode, DriverMode::kHolding);
  EXPECT_EQ(state->reason.find("holding: only silent"), 0u) << state->reason;
  // Its writer is gone (it stopped, or its lease ran out): the heartbeats say so, with why the
  // hold began; φ stays held.
  core_.SetControllersConnected(0);
  state = core_.Tick(9 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->reason.find("holding: no controller connected any more (at the hold: only silent"), 0u)
      << state->reason;
  EXPECT_EQ(Phi(*state), std::vector<double>({0.3, 0.2, 0.1}));
  // A controller connects again: the reason is the arbiter's own again, and it takes over.
  core_.SetControllersConnected(1);
  state = core_.Tick(15 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->reason.find("holding: only silent"), 0u) << state->reason;
  state = Send(core_, Command("only", 0, {0.31, 0.2, 0.1}, 2), 16 * kMs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->mode, DriverMode::kActive);
}

TEST_F(DriverCoreTest, BeforeAnyControllerTheReasonIsNoControllerYet) {
  core_.SetControllersConnected(0);
  EXPECT_EQ(core_.State(0).reason, "holding: no controller yet");
}

/// `primary` (priority 10) and `standby` (0) answer samples 1 … `samples` at 2 kHz, the primary
/// first (10 µs ahead); the time of the last sample.
int64_t PrimaryAndStandbyAnswer(DriverCore& core, int samples) {
  int64_t t = 0;
  for (int k = 1; k <= samples; ++k) {
    t = (k - 1) * 500 * kUs;
    Send(core, Command("primary", 10, {0.1, 0.1, 0.1}, k), t, 0);
    Send(core, Command("standby", 0, {0.1, 0.1, 0.1}, k), t + 10 * kUs, 0);
  }
  return t;
}

/// `state` applied the standby's answer to `sample` (φ_0 = `phi0`) in the place of the obeyed
/// primary's: the `count`-th stand-in.
void ExpectStandIn(const std::optional<DriverState>& state, uint64_t sample, double phi0, uint64_t count) {
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->obeyed_controller_id, "primary");
  EXPECT_EQ(state->applied_controller_id, "standby");
  EXPECT_EQ(state->stand_ins, count);
  EXPECT_EQ(state->answers_sample, sample);
  EXPECT_NEAR(Phi(*state)[0], phi0, 1e-12);
}

TEST_F(DriverCoreTest, AKilledPrimarysSamplesAreStoodInForAtOnceAndTheStandbyTakesOverAfterTheGrace) {
  // The standby commands other φ than the primary. When the primary stops answering, the
  // standby's answer stands in for each sample the primary owes one wait after it arrived (the
  // primary answered first until then: 0.2 ms, the least wait), long before the grace.
  int64_t t = PrimaryAndStandbyAnswer(core_, 50);
  const int64_t standby_at = t + 500 * kUs;
  Send(core_, Command("standby", 0, {0.1001, 0.1, 0.1}, 51), standby_at, 0);
  ASSERT_EQ(core_.obeyed(), "primary");
  EXPECT_EQ(core_.NextTickNs(), standby_at + ControllerArbiter::kMinStandInWaitNs);
  std::optional<DriverState> state;
  int64_t tick = standby_at;
  for (; tick < standby_at + 2 * kMs && !state; tick += 25 * kUs) state = core_.Tick(tick, 0);
  ExpectStandIn(state, 51, 0.1001, 1);
  EXPECT_LE(tick - standby_at, 225 * kUs) << "one wait after the standby's lone answer";
  // The next sample likewise; then the grace (1.2 ms after the first lone answer) ends and the
  // standby is obeyed, its latest answer already applied.
  Send(core_, Command("standby", 0, {0.1002, 0.1, 0.1}, 52), standby_at + 500 * kUs, 0);
  for (tick = standby_at + 500 * kUs, state.reset(); tick < standby_at + 2 * kMs && !state; tick += 25 * kUs) {
    state = core_.Tick(tick, 0);
  }
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->applied_controller_id, "standby");
  EXPECT_EQ(state->answers_sample, 52u);
  EXPECT_EQ(state->stand_ins, 2u);
  for (state.reset(); tick < standby_at + 3 * kMs && !state; tick += 25 * kUs) state = core_.Tick(tick, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->obeyed_controller_id, "standby");
  EXPECT_EQ(state->mode, DriverMode::kActive);
  EXPECT_EQ(state->answers_sample, 52u);
  EXPECT_NEAR(Phi(*state)[0], 0.1002, 1e-12);
  EXPECT_LE(tick - standby_at, 1250 * kUs) << "the grace, 1.2 ms, after the standby's first lone answer";
}

TEST_F(DriverCoreTest, AStandInIsAppliedWithTheStandbysNextAnswerIfTheTickerWokeLate) {
  int64_t t = PrimaryAndStandbyAnswer(core_, 50);
  // The primary is gone; the ticker does not run (a busy machine): the standby's answer to 52,
  // arriving after the wait for 51 is over, is applied as it arrives.
  EXPECT_FALSE(Send(core_, Command("standby", 0, {0.1001, 0.1, 0.1}, 51), t + 500 * kUs, 0).has_value());
  const auto state = Send(core_, Command("standby", 0, {0.1002, 0.1, 0.1}, 52), t + 1000 * kUs, 0);
  ExpectStandIn(state, 52, 0.1002, 1);
}

TEST_F(DriverCoreTest, APrimaryLateOnceLosesThatSampleToTheStandbyNotControl) {
  int64_t t = PrimaryAndStandbyAnswer(core_, 50);
  // Sample 51: the standby answers, the primary is 0.4 ms late.
  t += 500 * kUs;
  Send(core_, Command("standby", 0, {0.1001, 0.1, 0.1}, 51), t, 0);
  std::optional<DriverState> state;
  for (int64_t tick = t; tick < t + 400 * kUs && !state; tick += 25 * kUs) state = core_.Tick(tick, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->applied_controller_id, "standby");
  EXPECT_EQ(state->answers_sample, 51u);
  // The primary's late answer to 51 is its own: applied over the stand-in's.
  state = Send(core_, Command("primary", 10, {0.1002, 0.1, 0.1}, 51), t + 400 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->applied_controller_id, "primary");
  EXPECT_NEAR(Phi(*state)[0], 0.1002, 1e-12);
  // On time again: obeyed as ever, no switch, one stand-in.
  state = Send(core_, Command("primary", 10, {0.1003, 0.1, 0.1}, 52), t + 500 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->obeyed_controller_id, "primary");
  EXPECT_EQ(state->controller_switches, 1u);
  EXPECT_EQ(state->stand_ins, 1u);
  EXPECT_FALSE(Send(core_, Command("standby", 0, {0.1003, 0.1, 0.1}, 52), t + 510 * kUs, 0).has_value());
  for (int64_t tick = t + 510 * kUs; tick < t + 2 * kMs; tick += 25 * kUs) EXPECT_FALSE(core_.Tick(tick, 0));
}

TEST_F(DriverCoreTest, ANewControllerBeyondTheLimitIsRefusedWhileEveryKnownOneIsAlive) {
  const int limit = static_cast<int>(ControllerArbiter::kMaxControllers);
  for (int k = 1; k <= 5; ++k) {
    const int64_t t = k * 100 * kUs;
    for (int c = 0; c < limit; ++c) {
      Send(core_, Command(fmt::format("c{}", c), c == 0 ? 10 : 0, {0.1, 0.1, 0.1}, k), t + c * kUs, 0);
    }
  }
  const uint64_t rejected = core_.commands_rejected();
  EXPECT_FALSE(Send(core_, Command("newcomer", 100, {0.9, 0.9, 0.9}, 5), 600 * kUs, 0).has_value());
  EXPECT_EQ(core_.commands_rejected(), rejected + 1);
  EXPECT_NE(core_.last_rejection().find("64 controllers already on this bench"), std::string::npos)
      << core_.last_rejection();
  EXPECT_EQ(core_.obeyed(), "c0");
  EXPECT_EQ(backend_.Applied().phi, ControlVector::Constant(3, 0.1));
  // Once one of them is gone for good, there is room again.
  for (int k = 6; k <= 60; ++k) {
    const int64_t t = k * 100 * kUs;
    for (int c = 0; c < limit - 1; ++c) {
      Send(core_, Command(fmt::format("c{}", c), c == 0 ? 10 : 0, {0.1, 0.1, 0.1}, k), t + c * kUs, 0);
    }
  }
  auto state = Send(core_, Command("newcomer", 100, {0.2, 0.2, 0.2}, 60), 6 * kMs + 80 * kUs, 0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->obeyed_controller_id, "newcomer");
}

}  // namespace
}  // namespace dpc::services
