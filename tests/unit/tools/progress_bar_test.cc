#include "progress_bar.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

namespace dpc::tools {
namespace {

using Clock = ProgressBar::Clock;

/// A clock the test moves by hand.
class FakeClock {
 public:
  ProgressBar::Now Now() {
    return [this] { return now_; };
  }
  void Advance(Clock::duration step) { now_ += step; }

 private:
  Clock::time_point now_{std::chrono::seconds(1000)};
};

constexpr const char* kClearLine = "\r\033[K";

int CountOf(const std::string& text, const std::string& what) {
  int count = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++count;
  }
  return count;
}

// Every test captures stderr around the bar.
class ProgressBarTest : public ::testing::Test {
 protected:
  void SetUp() override { ::testing::internal::CaptureStderr(); }
  // Releases the capture if a test ended before reading it (only one capture may exist).
  void TearDown() override {
    if (capturing_) ::testing::internal::GetCapturedStderr();
  }
  std::string Captured() {
    capturing_ = false;
    return ::testing::internal::GetCapturedStderr();
  }

 private:
  bool capturing_ = true;
};

TEST_F(ProgressBarTest, DisabledBarWritesNothing) {
  {
    ProgressBar bar("dpc test", false);
    bar.Update(0, 100);
    bar.Update(50, 100);
    bar.Update(100, 100);
    bar.Finish();
  }
  EXPECT_EQ(Captured(), "");
}

TEST_F(ProgressBarTest, NothingToCountWritesNothing) {
  {
    ProgressBar bar("dpc test", true);
    bar.Update(0, 0);
    bar.Update(5, -1);
    bar.Finish();
  }
  EXPECT_EQ(Captured(), "");
}

TEST_F(ProgressBarTest, FirstUpdateDrawsLabelPercentageAndRate) {
  {
    ProgressBar bar("dpc test", true);
    bar.Update(25'000'000, 50'000'000);
  }
  const std::string text = Captured();
  EXPECT_EQ(text.rfind("\rdpc test [", 0), 0u) << text;
  EXPECT_NE(text.find(" 50%"), std::string::npos) << text;
  EXPECT_NE(text.find("25.0 M of 50.0 M samples"), std::string::npos) << text;
  EXPECT_NE(text.find("M/s"), std::string::npos) << text;
  EXPECT_NE(text.find("ETA"), std::string::npos) << text;
  EXPECT_EQ(text.find('\n'), std::string::npos) << "one line, redrawn in place";
  // Half of the 24-character bar is filled.
  EXPECT_EQ(CountOf(text, "█"), 12) << text;
  EXPECT_EQ(CountOf(text, "░"), 12) << text;
}

TEST_F(ProgressBarTest, RedrawsAtMostEvery100MillisecondsExceptAtCompletion) {
  FakeClock clock;
  {
    ProgressBar bar("dpc test", true, clock.Now());
    bar.Update(1, 10);
    clock.Advance(std::chrono::milliseconds(40));
    bar.Update(2, 10);
    clock.Advance(std::chrono::milliseconds(59));
    bar.Update(3, 10);  // 99 ms after the first draw
    bar.Update(10, 10);  // completion is always drawn
  }
  const std::string text = Captured();
  EXPECT_NE(text.find("100%"), std::string::npos) << text;
  EXPECT_EQ(CountOf(text, "\rdpc test ["), 2) << text;
  EXPECT_NE(text.find(" 10%"), std::string::npos) << text;
  EXPECT_EQ(text.find(" 20%"), std::string::npos) << text;
  EXPECT_EQ(text.find(" 30%"), std::string::npos) << text;
}

TEST_F(ProgressBarTest, RedrawsAfter100MillisecondsWithTheRateAndTheEta) {
  FakeClock clock;
  {
    ProgressBar bar("dpc test", true, clock.Now());
    bar.Update(1'000'000, 10'000'000);
    clock.Advance(std::chrono::milliseconds(100));
    bar.Update(4'000'000, 10'000'000);  // 4 M in 0.1 s: 40 M/s, 6 M left: 0.15 s
  }
  const std::string text = Captured();
  EXPECT_EQ(CountOf(text, "\rdpc test ["), 2) << text;
  EXPECT_NE(text.find(" 40%"), std::string::npos) << text;
  EXPECT_NE(text.find("40.0 M/s"), std::string::npos) << text;
  EXPECT_NE(text.find("ETA 0.1 s"), std::string::npos) << text;
}

TEST_F(ProgressBarTest, FinishClearsTheLineOnce) {
  {
    ProgressBar bar("dpc test", true);
    bar.Update(1, 2);
    bar.Finish();
    bar.Finish();  // nothing left to clear; neither has the destructor
  }
  const std::string text = Captured();
  EXPECT_EQ(CountOf(text, kClearLine), 1) << text;
  EXPECT_EQ(text.size() - text.rfind(kClearLine), std::string(kClearLine).size())
      << "the clear comes last";
}

TEST_F(ProgressBarTest, TheDestructorClearsADrawnLine) {
  { ProgressBar bar("dpc test", true); bar.Update(1, 2); }
  const std::string text = Captured();
  EXPECT_EQ(CountOf(text, kClearLine), 1) << text;
}

TEST_F(ProgressBarTest, FinishWithoutADrawWritesNothing) {
  {
    ProgressBar bar("dpc test", true);
    bar.Finish();
  }
  EXPECT_EQ(Captured(), "");
}

TEST_F(ProgressBarTest, DrawsAgainAfterFinish) {
  {
    ProgressBar bar("dpc test", true);
    bar.Update(1, 4);
    bar.Finish();
    bar.Update(2, 4);  // the line was cleared: the next update draws at once
  }
  const std::string text = Captured();
  EXPECT_EQ(CountOf(text, "\rdpc test ["), 2) << text;
  EXPECT_NE(text.find(" 50%"), std::string::npos) << text;
  EXPECT_EQ(CountOf(text, kClearLine), 2) << text;  // by Finish, then by the destructor
}

}  // namespace
}  // namespace dpc::tools
