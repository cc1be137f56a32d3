#include "controller_arbiter.h"

#include <gtest/gtest.h>

#include <limits>

namespace dpc::services {
namespace {

constexpr int64_t kUs = 1000;
constexpr int64_t kMs = 1000 * kUs;
using Verdict = ControllerArbiter::Verdict;

class ControllerArbiterTest : public ::testing::Test {
 protected:
  ControllerArbiter arbiter_{ControllerArbiter::Settings{1.2e-3, 8.0}};  // the mechanics at a short grace

  /// Primary (priority 10) and standby (0) answer samples first … last at 10 kHz. Returns the
  /// time of the last sample.
  int64_t BothAnswer(int first, int last) {
    int64_t t = 0;
    for (int k = first; k <= last; ++k) {
      t = (k - 1) * 100 * kUs;
      arbiter_.OnCommand("primary", 10, k, t);
      arbiter_.OnCommand("standby", 0, k, t + 10 * kUs);
    }
    return t;
  }
};

TEST_F(ControllerArbiterTest, HoldsUntilTheFirstCommandThenObeysIt) {
  EXPECT_TRUE(arbiter_.holding());
  EXPECT_EQ(arbiter_.reason(), "holding: no controller yet");
  EXPECT_EQ(arbiter_.NextCheckNs(), std::numeric_limits<int64_t>::max());
  EXPECT_EQ(arbiter_.OnCommand("A", 3, 1, 0), Verdict::kObey);
  EXPECT_EQ(arbiter_.obeyed(), "A");
  EXPECT_EQ(arbiter_.obeyed_priority(), 3);
  EXPECT_EQ(arbiter_.reason(), "obeying A (priority 3)");
  EXPECT_EQ(arbiter_.switches(), 1u);
}

TEST_F(ControllerArbiterTest, HigherPriorityTakesOverLowerIsIgnored) {
  EXPECT_EQ(arbiter_.OnCommand("low", 0, 1, 1 * kMs), Verdict::kObey);
  EXPECT_EQ(arbiter_.OnCommand("high", 5, 1, 1 * kMs + 10 * kUs), Verdict::kObey);
  EXPECT_EQ(arbiter_.obeyed(), "high");
  EXPECT_EQ(arbiter_.reason(), "obeying high (priority 5 over low)");
  EXPECT_EQ(arbiter_.switches(), 2u);
  EXPECT_EQ(arbiter_.OnCommand("low", 0, 2, 1 * kMs + 100 * kUs), Verdict::kIgnore);
  EXPECT_EQ(arbiter_.OnCommand("equal", 5, 2, 1 * kMs + 110 * kUs), Verdict::kIgnore) << "ties: the obeyed one";
}

TEST_F(ControllerArbiterTest, FailsOverWhenTheStandbyAnsweredSamplesThePrimaryDidNotForTheSilenceTimeout) {
  const int64_t last_primary = BothAnswer(1, 50);
  ASSERT_EQ(arbiter_.obeyed(), "primary");
  // The standby goes on at 10 kHz; the check runs when due (NextCheckNs) and on every command.
  int64_t switched_at = -1;
  for (int k = 51; k <= 100 && switched_at < 0; ++k) {
    const int64_t t = (k - 1) * 100 * kUs;
    for (int64_t tick = t; tick < t + 100 * kUs; tick += 25 * kUs) {
      if (tick == t + 25 * kUs) arbiter_.OnCommand("standby", 0, k, tick);
      if (arbiter_.Check(tick) || arbiter_.obeyed() == "standby") {
        switched_at = tick;
        break;
      }
    }
  }
  // The grace max(1.2 ms, 1.5 × 0.1 ms) after the standby answered sample 51 (at 5.025 ms),
  // the first one the primary did not: 1.325 ms after the primary's last command.
  const int64_t first_unanswered = last_primary + 125 * kUs;
  ASSERT_GT(switched_at, 0);
  EXPECT_GE(switched_at - first_unanswered, 1200 * kUs);
  EXPECT_LE(switched_at - first_unanswered, 1225 * kUs);
  EXPECT_EQ(arbiter_.obeyed(), "standby");
  EXPECT_NE(arbiter_.reason().find("primary silent for 1.32 ms"), std::string::npos) << arbiter_.reason();
  EXPECT_NE(arbiter_.reason().find("samples behind"), std::string::npos) << arbiter_.reason();
}

TEST_F(ControllerArbiterTest, TheNextCheckIsDueWhenTheObeyedControllersTimeoutEnds) {
  const int64_t last = BothAnswer(1, 50);
  // Nobody answered anything newer: its silence timeout, max(1.2 ms, 8 × 0.1 ms).
  EXPECT_EQ(arbiter_.NextCheckNs(), last + 1200 * kUs + 1);
  EXPECT_FALSE(arbiter_.Check(last + 1200 * kUs));
}

TEST_F(ControllerArbiterTest, TheNextCheckIsDueWhenTheObeyedControllersGraceEndsAfterTheOthersAnswered) {
  const int64_t last = BothAnswer(1, 50);
  const int64_t standby_answered = last + 100 * kUs;
  arbiter_.OnCommand("standby", 0, 51, standby_answered);
  EXPECT_EQ(arbiter_.NextCheckNs(), standby_answered + 1200 * kUs);
  EXPECT_FALSE(arbiter_.Check(standby_answered + 1200 * kUs - 1));
  EXPECT_EQ(arbiter_.obeyed(), "primary");
  EXPECT_TRUE(arbiter_.Check(standby_answered + 1200 * kUs));
  EXPECT_EQ(arbiter_.obeyed(), "standby");
}

TEST_F(ControllerArbiterTest, AtSlowRatesTheGraceIsOneAndAHalfCommandIntervals) {
  // At 100 Hz a primary answering 5 ms after the standby is slower, not dead.
  int64_t t = 0;
  for (int k = 1; k <= 50; ++k) {
    t = (k - 1) * 10 * kMs;
    arbiter_.OnCommand("standby", 0, k, t);
    if (k > 2) {
      EXPECT_FALSE(arbiter_.Check(t + 4 * kMs));  // once the intervals are known
    }
    arbiter_.OnCommand("primary", 10, k, t + 5 * kMs);
    ASSERT_EQ(arbiter_.obeyed(), "primary") << "sample " << k;
  }
  // Killed after sample 50: the standby answers 51 at t + 10 ms; the grace is 15 ms from then.
  arbiter_.OnCommand("standby", 0, 51, t + 10 * kMs);
  EXPECT_FALSE(arbiter_.Check(t + 10 * kMs + 15 * kMs - 1 * kUs));
  arbiter_.OnCommand("standby", 0, 52, t + 20 * kMs);
  EXPECT_TRUE(arbiter_.Check(t + 10 * kMs + 15 * kMs + 1 * kUs));
  EXPECT_EQ(arbiter_.obeyed(), "standby");
}

TEST_F(ControllerArbiterTest, AStandbyOneSampleAheadAllTheTimeIsNoFailure) {
  // At a high rate the standby may answer sample k + 1 before the primary's answer to k
  // arrives: the primary is always "behind", never for long.
  int64_t t = 0;
  for (int k = 1; k <= 200; ++k, t += 100 * kUs) {
    arbiter_.OnCommand("standby", 0, k + 1, t);
    arbiter_.OnCommand("primary", 10, k, t + 60 * kUs);
    EXPECT_FALSE(arbiter_.Check(t + 80 * kUs));
    ASSERT_EQ(arbiter_.obeyed(), "primary") << "sample " << k;
  }
}

TEST_F(ControllerArbiterTest, TheStandInWaitFollowsHowLateTheObeyedControllerUsuallyAnswers) {
  // The primary answers every sample 160 µs after the standby: the wait is that, its deviation
  // (none once steady) and the margin, so its answers are waited for; a primary that answers
  // first gets the least wait; none is longer than half the grace.
  EXPECT_EQ(arbiter_.StandInWaitNs(), 0) << "holding";
  int64_t t = 0;
  for (int k = 1; k <= 200; ++k, t += 100 * kUs) {
    arbiter_.OnCommand("standby", 0, k + 1, t);
    arbiter_.OnCommand("primary", 10, k, t + 60 * kUs);
  }
  EXPECT_EQ(arbiter_.LastAnswered("primary"), 200u);
  EXPECT_EQ(arbiter_.LastAnswered("nobody"), 0u);
  EXPECT_NEAR(static_cast<double>(arbiter_.StandInWaitNs()), 260e3, 15e3);
  ControllerArbiter first{ControllerArbiter::Settings{1.2e-3, 8.0}};
  for (int k = 1; k <= 50; ++k) {
    first.OnCommand("primary", 10, k, k * 100 * kUs);
    first.OnCommand("standby", 0, k, k * 100 * kUs + 10 * kUs);
  }
  EXPECT_EQ(first.StandInWaitNs(), ControllerArbiter::kMinStandInWaitNs);
  ControllerArbiter slow{ControllerArbiter::Settings{1.2e-3, 8.0}};
  for (int k = 1; k <= 50; ++k) {
    slow.OnCommand("standby", 0, k, k * 100 * kUs);
    slow.OnCommand("primary", 10, k, k * 100 * kUs + 5 * kMs);
  }
  EXPECT_EQ(slow.StandInWaitNs(), 600 * kUs) << "half the 1.2-ms grace";
  ControllerArbiter short_grace{ControllerArbiter::Settings{0.6e-3, 8.0}};
  for (int k = 1; k <= 50; ++k) {
    short_grace.OnCommand("standby", 0, k, k * 100 * kUs);
    short_grace.OnCommand("primary", 10, k, k * 100 * kUs + 5 * kMs);
  }
  EXPECT_EQ(short_grace.StandInWaitNs(), 300 * kUs) << "half the 0.6-ms grace";
  ControllerArbiter default_grace{ControllerArbiter::Settings{}};
  for (int k = 1; k <= 50; ++k) {
    default_grace.OnCommand("standby", 0, k, k * 100 * kUs);
    default_grace.OnCommand("primary", 10, k, k * 100 * kUs + 5 * kMs);
  }
  EXPECT_EQ(default_grace.StandInWaitNs(), ControllerArbiter::kMaxStandInWaitNs) << "not half the 10-ms grace";
}

TEST_F(ControllerArbiterTest, AStallOfEveryoneHoldsThenGivesControlBackToTheSameController) {
  // No samples for 5 ms (a stalled polarimeter, or the whole machine): nobody answers, so the
  // silence is nobody's failure. On resumption the standby's command happens to come first.
  const int64_t t = BothAnswer(1, 50);
  const uint64_t switches = arbiter_.switches();
  ASSERT_TRUE(arbiter_.Check(t + 3 * kMs));
  EXPECT_TRUE(arbiter_.holding());
  EXPECT_NE(arbiter_.reason().find("primary silent"), std::string::npos) << arbiter_.reason();
  EXPECT_NE(arbiter_.reason().find("primary gets control back first"), std::string::npos);
  EXPECT_EQ(arbiter_.OnCommand("standby", 0, 51, t + 5 * kMs), Verdict::kAnswerOnly);
  EXPECT_TRUE(arbiter_.holding());
  EXPECT_EQ(arbiter_.OnCommand("primary", 10, 51, t + 5 * kMs + 10 * kUs), Verdict::kObey);
  EXPECT_EQ(arbiter_.obeyed(), "primary");
  EXPECT_EQ(arbiter_.switches(), switches + 1) << "holding → primary again; the standby never obeyed";
}

TEST_F(ControllerArbiterTest, ASuspendedControllerThatFellBehindLosesItsPlace) {
  // Holding for "only" after a general silence; "next" starts at 10 kHz. Once "next" has
  // answered samples "only" did not for the grace (1.2 ms), it is obeyed.
  arbiter_.OnCommand("only", 0, 1, 0);
  ASSERT_TRUE(arbiter_.Check(3 * kMs));
  ASSERT_TRUE(arbiter_.holding());
  int64_t obeyed_at = -1;
  for (int k = 2; k <= 50 && obeyed_at < 0; ++k) {
    const int64_t t = 20 * kMs + (k - 2) * 100 * kUs;
    if (arbiter_.OnCommand("next", 0, k, t) == Verdict::kObey) obeyed_at = t;
  }
  EXPECT_EQ(arbiter_.obeyed(), "next");
  EXPECT_GE(obeyed_at - 20 * kMs, 1200 * kUs);
  EXPECT_LE(obeyed_at - 20 * kMs, 1300 * kUs);
  EXPECT_NE(arbiter_.reason().find("only silent"), std::string::npos) << arbiter_.reason();
}

TEST_F(ControllerArbiterTest, ARestartedBenchLeavesNobodyBehind) {
  BothAnswer(1, 50);
  arbiter_.OnBenchRestart();
  // A new run: samples 1, 2, 3 … again, the standby's answer first each time.
  for (int k = 1; k <= 30; ++k) {
    const int64_t t = 5 * kMs + k * 100 * kUs;
    EXPECT_EQ(arbiter_.OnCommand("standby", 0, k, t), Verdict::kIgnore);
    EXPECT_EQ(arbiter_.OnCommand("primary", 10, k, t + 10 * kUs), Verdict::kObey);
    EXPECT_FALSE(arbiter_.Check(t + 50 * kUs));
    ASSERT_EQ(arbiter_.obeyed(), "primary") << "sample " << k;
  }
}

TEST_F(ControllerArbiterTest, WithoutAnyOtherControllerItHoldsAndSaysWhy) {
  arbiter_.OnCommand("only", 0, 1, 0);
  arbiter_.OnCommand("other", -1, 2, 10 * kUs);   // a lower-priority one that stops too
  ASSERT_TRUE(arbiter_.Check(3 * kMs));
  EXPECT_TRUE(arbiter_.holding());
  arbiter_.Hold("holding: backend x failed: lost");
  EXPECT_EQ(arbiter_.reason(), "holding: backend x failed: lost");
}

TEST_F(ControllerArbiterTest, KeepsABoundedNumberOfRecordsAndNeverDropsTheObeyedOne) {
  arbiter_.OnCommand("main", 100, 1, 0);
  for (int i = 0; i < 1000; ++i) {
    arbiter_.OnCommand("stranger" + std::to_string(i), 0, 1, (i + 1) * kUs);
  }
  EXPECT_EQ(arbiter_.obeyed(), "main");
  EXPECT_EQ(arbiter_.OnCommand("main", 100, 2, 2 * kMs), Verdict::kObey);
  // Answers numbered near 2^64 cost bounded work.
  arbiter_.OnCommand("late", 0, std::numeric_limits<uint64_t>::max(), 2 * kMs + 1);
  EXPECT_EQ(arbiter_.obeyed(), "main");
}

}  // namespace
}  // namespace dpc::services
