#include "progress_bar.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

namespace dpc::tools {
namespace {

using Clock = std::chrono::steady_clock;

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
  Clock::duration elapsed{};
  {
    ProgressBar bar("dpc test", true);
    const Clock::time_point start = Clock::now();
    bar.Update(1, 10);
    bar.Update(2, 10);
    bar.Update(3, 10);
    elapsed = Clock::now() - start;
    bar.Update(10, 10);  // completion is always drawn
  }
  const std::string text = Captured();
  EXPECT_NE(text.find("100%"), std::string::npos) << text;
  if (elapsed >= std::chrono::milliseconds(100)) {
    GTEST_SKIP() << "three updates took 100 ms here; the redraw interval cannot be checked";
  }
  EXPECT_EQ(CountOf(text, "\rdpc test ["), 2) << text;
  EXPECT_NE(text.find(" 10%"), std::string::npos) << text;
  EXPECT_EQ(text.find(" 20%"), std::string::npos) << text;
  EXPECT_EQ(text.find(" 30%"), std::string::npos) << text;
}

TEST_F(ProgressBarTest, RedrawsAfter100Milliseconds) {
  {
    ProgressBar bar("dpc test", true);
    bar.Update(1, 10);
    std::this_thread::sleep_for(std::chrono::milliseconds(120));
    bar.Update(4, 10);
  }
  const std::string text = Captured();
  EXPECT_EQ(CountOf(text, "\rdpc test ["), 2) << text;
  EXPECT_NE(text.find(" 40%"), std::string::npos) << text;
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
