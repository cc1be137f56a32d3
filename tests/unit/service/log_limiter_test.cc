#include "log_limiter.h"
#include "service_runtime.h"

#include <gtest/gtest.h>

#include <memory>
#include <sstream>
#include <string>

#include <spdlog/sinks/ostream_sink.h>

namespace dpc::services {
namespace {

using namespace std::chrono_literals;

/// The default logger writes into `lines_` while the test runs.
class LogLimiterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    previous_ = spdlog::default_logger();
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(lines_);
    auto logger = std::make_shared<spdlog::logger>("log_limiter_test", sink);
    logger->set_pattern("%l %v");
    spdlog::set_default_logger(logger);
  }
  void TearDown() override { spdlog::set_default_logger(previous_); }

  int64_t now_ns_ = 1'000'000'000;
  LogLimiter limiter_{5s, [this] { return now_ns_; }};
  std::ostringstream lines_;
  std::shared_ptr<spdlog::logger> previous_;
};

TEST_F(LogLimiterTest, TheFirstLineOfAKeyIsLoggedRepeatsWithinTheIntervalAreCounted) {
  EXPECT_TRUE(limiter_.Log(spdlog::level::warn, "frozen", "frozen: no sample for 25 ms"));
  for (int i = 0; i < 49; ++i) {
    now_ns_ += 20'000'000;  // a status every 20 ms
    EXPECT_FALSE(limiter_.Log(spdlog::level::warn, "frozen", "frozen: no sample for more"));
  }
  EXPECT_EQ(limiter_.suppressed("frozen"), 49u);
  EXPECT_EQ(lines_.str(), "warning frozen: no sample for 25 ms\n");
  // 5 s after the first line the next one says how many it stands for.
  now_ns_ = 1'000'000'000 + 5'000'000'000;
  EXPECT_TRUE(limiter_.Log(spdlog::level::warn, "frozen", "frozen: no sample for 5025 ms"));
  EXPECT_NE(lines_.str().find("frozen: no sample for 5025 ms (49 more like this in the last 5.0 s)"),
            std::string::npos)
      << lines_.str();
  EXPECT_EQ(limiter_.suppressed("frozen"), 0u);
}

TEST_F(LogLimiterTest, AnotherKeyIsLoggedAtOnce) {
  EXPECT_TRUE(limiter_.Log(spdlog::level::info, "tracking", "tracking"));
  EXPECT_TRUE(limiter_.Log(spdlog::level::warn, "frozen", "frozen: no sample for 25 ms"));
  EXPECT_FALSE(limiter_.Log(spdlog::level::info, "tracking", "tracking"));
  EXPECT_EQ(lines_.str(), "info tracking\nwarning frozen: no sample for 25 ms\n");
}

TEST_F(LogLimiterTest, KeepsABoundedNumberOfKeys) {
  for (size_t i = 0; i < 10 * LogLimiter::kMaxKeys; ++i) {
    now_ns_ += 1000;
    EXPECT_TRUE(limiter_.Log(spdlog::level::info, "key " + std::to_string(i), "line"));
  }
  // The first key was forgotten long ago: it logs again at once.
  EXPECT_TRUE(limiter_.Log(spdlog::level::info, "key 0", "line"));
}

TEST_F(LogLimiterTest, AKeyOfAMessageIgnoresItsFiguresOnly) {
  EXPECT_EQ(LogLimiter::KeyOf("holding: main silent for 3.25 ms, 12 samples behind"),
            "holding: main silent for # ms, # samples behind");
  EXPECT_EQ(LogLimiter::KeyOf("holding: main silent for 3.25 ms, 12 samples behind"),
            LogLimiter::KeyOf("holding: main silent for 41.7 ms, 3 samples behind"));
  EXPECT_NE(LogLimiter::KeyOf("holding: no controller yet"),
            LogLimiter::KeyOf("holding: main silent for 3.25 ms, 12 samples behind"));
  EXPECT_EQ(LogLimiter::KeyOf("1,000.5 and 2. end."), "# and #. end.");
  EXPECT_EQ(LogLimiter::KeyOf(""), "");
  // Two reasons of the same kind share a key; a new kind logs at once, within the interval.
  EXPECT_TRUE(limiter_.Log(spdlog::level::warn, LogLimiter::KeyOf("holding: no controller yet"),
                           "holding: no controller yet"));
  now_ns_ += 1'000'000'000;
  EXPECT_TRUE(limiter_.Log(spdlog::level::warn, LogLimiter::KeyOf("holding: main silent for 3.2 ms"),
                           "holding: main silent for 3.2 ms"));
  EXPECT_FALSE(limiter_.Log(spdlog::level::warn, LogLimiter::KeyOf("holding: main silent for 9.9 ms"),
                            "holding: main silent for 9.9 ms"));
}

TEST_F(LogLimiterTest, AKindOfAMessageIsItsTextBeforeItsFirstCauseOrFigure) {
  EXPECT_EQ(LogLimiter::KindOf("frozen: no sample for 25 ms"), "frozen");
  EXPECT_EQ(LogLimiter::KindOf("frozen: no sample for 25 ms"), LogLimiter::KindOf("frozen: no sample for 45 ms"));
  EXPECT_EQ(LogLimiter::KindOf("unusable device description: 0 stages"),
            LogLimiter::KindOf("unusable device description: a NaN axis"));
  EXPECT_EQ(LogLimiter::KindOf("standby (following the applied φ)"), "standby ");
  EXPECT_EQ(LogLimiter::KindOf("tracking"), "tracking");
  EXPECT_EQ(LogLimiter::KindOf("3 stages"), "");
  EXPECT_NE(LogLimiter::KindOf("tracking"), LogLimiter::KindOf("waiting for samples"));
}

TEST_F(LogLimiterTest, PeerEventsAreLoggedUpToABudgetPerWindowThenCounted) {
  PeerLog log([this] { return now_ns_; });
  log(false, "participant discovered: a (dpc-driver/bench1)");
  log(true, "participant refused by DDS Security: b (intruder)");
  EXPECT_EQ(lines_.str(),
            "info participant discovered: a (dpc-driver/bench1)\n"
            "warning participant refused by DDS Security: b (intruder)\n");
  // A peer creating participants in a loop: the budget of the window, then silence.
  for (int i = 0; i < 100; ++i) log(true, "participant refused by DDS Security: flood");
  size_t lines = 0;
  for (char c : lines_.str()) lines += c == '\n';
  EXPECT_EQ(lines, static_cast<size_t>(PeerLog::kLines));
  // The next window's first line counts what was not shown.
  now_ns_ += PeerLog::kWindowNs;
  log(false, "participant gone: a (dpc-driver/bench1)");
  EXPECT_NE(lines_.str().find("participant gone: a (dpc-driver/bench1) (82 peer events before it not shown)"),
            std::string::npos)
      << lines_.str();
}

}  // namespace
}  // namespace dpc::services
