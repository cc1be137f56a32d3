// HandshakeWatchdog: when a secured service makes its participant again by itself (a handshake
// with no outcome, and no progress, both for kStallNs; or a peer back after its lease expired),
// and how often at most; and what an observer (a `dpc` command) is told.
#include "dpc/bus/handshake_watchdog.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace dpc::bus {
namespace {

constexpr int64_t kS = 1'000'000'000;
constexpr int64_t kStall = HandshakeWatchdog::kStallNs;
const std::vector<std::string> kNone;
const std::vector<std::string> kGhost = {"01.0f.aa (dpc-test-ghost)"};

TEST(HandshakeWatchdogTest, LooksAtMostOnceASecond) {
  HandshakeWatchdog watchdog;
  EXPECT_TRUE(watchdog.Due(100 * kS));
  EXPECT_FALSE(watchdog.Due(100 * kS + kS / 2));
  EXPECT_TRUE(watchdog.Due(101 * kS));
  EXPECT_FALSE(watchdog.Due(101 * kS));
}

TEST(HandshakeWatchdogTest, AsksForAReloadOnlyWhenAHandshakeStalledAndTheServiceStarves) {
  HandshakeWatchdog watchdog;
  const int64_t start = 1000 * kS;
  // A working service (progress just under kStallNs ago) with a stalled peer: nothing.
  EXPECT_EQ(watchdog.Judge(start, start - kStall + kS / 10, kGhost), "");
  // A starved service with no stalled peer (nobody there, or every handshake finished): nothing.
  EXPECT_EQ(watchdog.Judge(start, start - 60 * kS, kNone), "");
  // Both: a reload, named and explained.
  const std::string why = watchdog.Judge(start, start - 12 * kS, kGhost);
  EXPECT_NE(why.find("01.0f.aa (dpc-test-ghost)"), std::string::npos) << why;
  EXPECT_NE(why.find("no progress for 12 s"), std::string::npos) << why;
  EXPECT_NE(why.find("not before 30 s"), std::string::npos) << why;
  EXPECT_EQ(watchdog.reloads(), 1u);
}

TEST(HandshakeWatchdogTest, AStarvedServiceReloadsLessAndLessOftenUntilItWorksAgain) {
  HandshakeWatchdog watchdog;
  const int64_t progress = 0;
  std::vector<int64_t> reloads_s;
  for (int64_t t = 10 * kS; t <= 2000 * kS; t += kS) {
    if (!watchdog.Judge(t, progress, kGhost).empty()) reloads_s.push_back(t / kS);
  }
  // 30, 60, 120, 240, 480 s apart, then 600 s (the longest).
  EXPECT_EQ(reloads_s, (std::vector<int64_t>{10, 40, 100, 220, 460, 940, 1540}));
  // It works again: a new stall heals as soon as the first did, then 30 s later.
  EXPECT_EQ(watchdog.Judge(2001 * kS, 2000 * kS, kGhost), "");
  const int64_t healed = 2001 * kS + kStall;
  EXPECT_EQ(watchdog.Judge(healed - kS, 2001 * kS, kGhost), "");  // not starved for kStallNs yet
  EXPECT_NE(watchdog.Judge(healed, 2001 * kS, kGhost), "");
  EXPECT_EQ(watchdog.Judge(healed + 29 * kS, 2001 * kS, kGhost), "");
  EXPECT_NE(watchdog.Judge(healed + 30 * kS, 2001 * kS, kGhost), "");
}

TEST(HandshakeWatchdogTest, NamesAtMostThreePeersAndCountsTheRest) {
  HandshakeWatchdog watchdog;
  const std::string why = watchdog.Judge(100 * kS, 0, {"a (1)", "b (2)", "c (3)", "d (4)", "e (5)"});
  EXPECT_NE(why.find("a (1), b (2), c (3) and 2 more"), std::string::npos) << why;
  EXPECT_EQ(why.find("d (4)"), std::string::npos) << why;
}

TEST(HandshakeWatchdogTest, AnObserverIsToldThatItHearsNothingFromTheStalledPeer) {
  HandshakeWatchdog watchdog(HandshakeWatchdog::Starving::kObserver);
  // Its progress: when it last had no handshake pending.
  EXPECT_EQ(watchdog.Judge(100 * kS, 100 * kS - kStall + kS, kGhost), "");
  const std::string why = watchdog.Judge(100 * kS, 100 * kS - kStall - kS, kGhost);
  EXPECT_NE(why.find("01.0f.aa (dpc-test-ghost) has had no outcome for " + std::to_string(kStall / kS) +
                     " s or more, so nothing of theirs reaches "
                     "this command (a Fast DDS 2.9 handshake stall"),
            std::string::npos)
      << why;
  EXPECT_EQ(why.find("this service"), std::string::npos) << why;
  // Every handshake settled since: the back-off starts over.
  EXPECT_EQ(watchdog.Judge(105 * kS, 104 * kS, kNone), "");
  EXPECT_NE(watchdog.Judge(104 * kS + kStall, 104 * kS, kGhost), "");
}

TEST(HandshakeWatchdogTest, APeerBackAfterItsLeaseExpiredAndPendingMakesAWorkingServiceReloadOnce) {
  HandshakeWatchdog watchdog;
  const int64_t now = 1000 * kS;
  EXPECT_EQ(watchdog.JudgeReturning(now, kNone), "");
  // Whatever the service's progress (Judge is not asked): a reload, named and explained.
  const std::string why = watchdog.JudgeReturning(now, kGhost);
  EXPECT_NE(why.find("the security handshake with 01.0f.aa (dpc-test-ghost), back after its lease had expired, has "
                     "had no outcome for " +
                     std::to_string(kStall / kS) + " s or more"),
            std::string::npos)
      << why;
  EXPECT_EQ(watchdog.reloads(), 1u);
  // The next one not before 30 s (the new participant never saw the peer leave, so it would not
  // list it as returning anyway).
  EXPECT_EQ(watchdog.JudgeReturning(now + 29 * kS, kGhost), "");
  EXPECT_NE(watchdog.JudgeReturning(now + 30 * kS, kGhost), "");
  // It does not hold back the other judgement: a starved service with a stalled peer still heals.
  EXPECT_NE(watchdog.Judge(now + 31 * kS, 0, kGhost), "");
}

}  // namespace
}  // namespace dpc::bus
