// The loop guard: a loop that stops turning, or a stop that does not end, is reported once and
// ends the process; a loop that turns, a limit of 0, and a process stopped as a whole are not.
#include "dpc/cli/loop_guard.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <thread>

#include <cstdio>

namespace dpc::cli {
namespace {

using namespace std::chrono_literals;

constexpr int64_t kMs = 1'000'000;

TEST(StuckJudgeTest, ALoopThatTurnsIsNeverStuck) {
  StuckJudge judge(1000 * kMs, 8000 * kMs);
  for (int64_t t = 0; t < 60'000; t += 100) EXPECT_EQ(judge.Look(t * kMs, t / 100, false, "its ticks"), "") << t;
}

TEST(StuckJudgeTest, ALoopThatStopsTurningIsStuckAfterTheLimitAndTheMessageSaysWhere) {
  StuckJudge judge(1000 * kMs, 8000 * kMs);
  EXPECT_EQ(judge.Look(0, 5, false, "its ticks"), "");
  EXPECT_EQ(judge.Look(100 * kMs, 6, false, "its ticks"), "");  // the last turn seen
  for (int64_t t = 200; t < 1100; t += 100) EXPECT_EQ(judge.Look(t * kMs, 6, false, "a reload"), "") << t;
  const std::string why = judge.Look(1100 * kMs, 6, false, "a reload");
  EXPECT_NE(why.find("its loop has not turned for 1.0 s (stuck in: a reload)"), std::string::npos) << why;
  EXPECT_NE(why.find("--stuck-exit-s"), std::string::npos) << why;
}

TEST(StuckJudgeTest, ALimitOfZeroNeverJudgesTheLoop) {
  StuckJudge judge(0, 8000 * kMs);
  for (int64_t t = 0; t < 60'000; t += 100) EXPECT_EQ(judge.Look(t * kMs, 0, false, "x"), "") << t;
}

TEST(StuckJudgeTest, AStopMustEndWithinTheGraceWhateverTheLoopDoes) {
  StuckJudge judge(0, 8000 * kMs);
  EXPECT_EQ(judge.Look(0, 0, false, "x"), "");
  for (int64_t t = 100; t < 8100; t += 100) EXPECT_EQ(judge.Look(t * kMs, t, true, "x"), "") << t;
  const std::string why = judge.Look(8100 * kMs, 8100, true, "the deletion of its DDS entities");
  EXPECT_NE(why.find("did not end within 8.0 s of being asked to stop (stuck in: the deletion of its DDS entities)"),
            std::string::npos)
      << why;
}

TEST(StuckJudgeTest, AProcessStoppedAsAWholeIsNotStuckWhenItResumes) {
  // SIGSTOP for 30 s: the guard's own looks stop too; after SIGCONT the loop gets a whole new
  // limit (and a stop a whole new grace) before anything is judged.
  StuckJudge judge(1000 * kMs, 8000 * kMs);
  EXPECT_EQ(judge.Look(0, 1, false, "x"), "");
  EXPECT_EQ(judge.Look(30'000 * kMs, 1, true, "x"), "");
  for (int64_t t = 30'100; t < 38'000; t += 100) EXPECT_EQ(judge.Look(t * kMs, 1, true, "x"), "") << t;
  EXPECT_NE(judge.Look(38'000 * kMs, 1, true, "x"), "");
  StuckJudge loop(1000 * kMs, 8000 * kMs);
  EXPECT_EQ(loop.Look(0, 1, false, "x"), "");
  EXPECT_EQ(loop.Look(30'000 * kMs, 1, false, "x"), "");
  EXPECT_EQ(loop.Look(30'900 * kMs, 1, false, "x"), "");
  EXPECT_NE(loop.Look(31'000 * kMs, 1, false, "x"), "");
}

TEST(StuckJudgeTest, AHeartbeatSilentForItsLimitIsStuckOneThatBeatsOrIsAbsentIsNot) {
  StuckJudge judge(0, 8000 * kMs);
  for (int64_t t = 0; t <= 10'000; t += 100) {
    EXPECT_EQ(judge.Look(t * kMs, 1, false, "x"), "");
    EXPECT_EQ(judge.LookAtBeat(t * kMs, (t - 50) * kMs, 3000 * kMs, "its event thread"), "") << t;
    EXPECT_EQ(judge.LookAtBeat(t * kMs, std::nullopt, 3000 * kMs, "its event thread"), "") << "nothing to watch";
  }
  // The last beat at 10 s: not stuck at 12.9 s, stuck at 13 s, and the message says what.
  for (int64_t t = 10'100; t < 13'000; t += 100) {
    EXPECT_EQ(judge.Look(t * kMs, 1, false, "x"), "");
    EXPECT_EQ(judge.LookAtBeat(t * kMs, 10'000 * kMs, 3000 * kMs, "its event thread"), "") << t;
  }
  EXPECT_EQ(judge.Look(13'000 * kMs, 1, false, "x"), "");
  const std::string why = judge.LookAtBeat(13'000 * kMs, 10'000 * kMs, 3000 * kMs, "its event thread");
  EXPECT_NE(why.find("stuck: its event thread has not run for 3.0 s"), std::string::npos) << why;
  EXPECT_EQ(judge.LookAtBeat(13'000 * kMs, 10'000 * kMs, 0, "its event thread"), "") << "a limit of 0: off";
}

TEST(StuckJudgeTest, AHeartbeatIsJudgedFromTheWindowAfterAPauseOfTheWholeProcess) {
  // SIGSTOP for 30 s: the heartbeat's thread did not run either; it gets a whole new limit.
  StuckJudge judge(0, 8000 * kMs);
  EXPECT_EQ(judge.LookAtBeat(0, 0, 3000 * kMs, "x"), "") << "before the first look";
  EXPECT_EQ(judge.Look(0, 1, false, "x"), "");
  EXPECT_EQ(judge.Look(30'000 * kMs, 1, false, "x"), "");
  EXPECT_EQ(judge.LookAtBeat(30'000 * kMs, 0, 3000 * kMs, "x"), "");
  for (int64_t t = 30'100; t < 33'000; t += 100) {
    EXPECT_EQ(judge.Look(t * kMs, 1, false, "x"), "");
    EXPECT_EQ(judge.LookAtBeat(t * kMs, 0, 3000 * kMs, "x"), "") << t;
  }
  EXPECT_EQ(judge.Look(33'000 * kMs, 1, false, "x"), "");
  EXPECT_NE(judge.LookAtBeat(33'000 * kMs, 0, 3000 * kMs, "x"), "");
}

/// A guard whose action records the message instead of ending the process.
struct Recorded {
  std::mutex mutex;
  std::string why;
  std::atomic<int> calls{0};
  LoopGuard::OnStuck Action() {
    return [this](const std::string& text) {
      std::lock_guard<std::mutex> lock(mutex);
      why = text;
      ++calls;
    };
  }
};

TEST(LoopGuardTest, ATurningLoopIsLeftAloneAndAStuckOneIsReportedOnce) {
  Recorded recorded;
  {
    LoopGuard guard(1.0, 8.0, recorded.Action());
    const auto until = std::chrono::steady_clock::now() + 2s;
    while (std::chrono::steady_clock::now() < until) {
      guard.Turn();
      std::this_thread::sleep_for(5ms);
    }
    EXPECT_EQ(recorded.calls.load(), 0);
    guard.Phase("a call that never returns");
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (recorded.calls.load() == 0 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(10ms);
    }
    std::this_thread::sleep_for(500ms);  // no second report
  }
  EXPECT_EQ(recorded.calls.load(), 1);
  EXPECT_NE(recorded.why.find("(stuck in: a call that never returns)"), std::string::npos) << recorded.why;
}

TEST(LoopGuardTest, AHeartbeatThatStopsIsReportedWhileTheLoopTurnsButNotOnceStopping) {
  Recorded recorded;
  std::atomic<int64_t> beat_ns{0};
  const auto now_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  };
  {
    LoopGuard guard(1.0, 8.0, recorded.Action(), {},
                    Heartbeat{[&beat_ns] { return std::optional<int64_t>(beat_ns.load()); }, 1.0, "the beat"});
    const auto beat_until = std::chrono::steady_clock::now() + 1500ms;
    while (std::chrono::steady_clock::now() < beat_until) {
      guard.Turn();
      beat_ns = now_ns();
      std::this_thread::sleep_for(5ms);
    }
    EXPECT_EQ(recorded.calls.load(), 0) << "it beats";
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (recorded.calls.load() == 0 && std::chrono::steady_clock::now() < deadline) {
      guard.Turn();  // the loop turns; only the heartbeat stopped
      std::this_thread::sleep_for(5ms);
    }
  }
  EXPECT_EQ(recorded.calls.load(), 1);
  EXPECT_NE(recorded.why.find("stuck: the beat has not run for"), std::string::npos) << recorded.why;

  Recorded stopping;
  LoopGuard guard(0.0, 30.0, stopping.Action(), {},
                  Heartbeat{[] { return std::optional<int64_t>(0); }, 0.5, "the beat"});
  guard.Stopping();  // a stop has its own grace: the deletion of the participants stops the beats
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(stopping.calls.load(), 0) << stopping.why;
}

TEST(LoopGuardTest, AStopThatDoesNotEndIsReported) {
  Recorded recorded;
  LoopGuard guard(0.0, 1.0, recorded.Action());
  guard.Stopping();
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (recorded.calls.load() == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
  std::lock_guard<std::mutex> lock(recorded.mutex);
  EXPECT_NE(recorded.why.find("did not end within"), std::string::npos) << recorded.why;
}

TEST(LoopGuardTest, AStopFlagThatASignalHandlerSetsCountsAsAStop) {
  Recorded recorded;
  std::atomic<bool> flag{false};
  LoopGuard guard(0.0, 1.0, recorded.Action(), [&flag] { return flag.load(); });
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(recorded.calls.load(), 0) << "no stop asked yet";
  flag = true;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (recorded.calls.load() == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(recorded.calls.load(), 1);
}

TEST(LoopGuardDeathTest, ExitAfterSayingSaysAndExitsWithTheCode) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitAfterSaying([] { std::fputs("stuck: said\n", stderr); }, 1), ::testing::ExitedWithCode(1),
              "stuck: said");
  // A saying that never ends does not keep the process: it exits after 1 s all the same.
  EXPECT_EXIT(ExitAfterSaying([] { for (;;) std::this_thread::sleep_for(1s); }, 3), ::testing::ExitedWithCode(3), "");
}

}  // namespace
}  // namespace dpc::cli
