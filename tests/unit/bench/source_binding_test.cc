#include "dpc/bench/source_binding.h"

#include <gtest/gtest.h>

#include <vector>

namespace dpc {
namespace {

constexpr int64_t kMs = 1'000'000;

SourceId Source(uint8_t last) {
  SourceId id{};
  id[0] = 0x01;
  id[11] = last;
  return id;
}

TEST(SourceBindingTest, TheFirstSourceIsBoundAndEveryOtherRefusedWhileItTalks) {
  SourceBinding binding(100 * kMs);
  EXPECT_FALSE(binding.bound());
  EXPECT_TRUE(binding.Accept(Source(1), 0));
  EXPECT_TRUE(binding.bound());
  EXPECT_EQ(binding.source(), Source(1));
  for (int64_t t = 5 * kMs; t < 2000 * kMs; t += 5 * kMs) {
    EXPECT_TRUE(binding.Accept(Source(1), t));
    EXPECT_FALSE(binding.Accept(Source(2), t + 1)) << t;
  }
  EXPECT_EQ(binding.refused(), 399u);
  EXPECT_EQ(binding.last_refused(), Source(2));
  EXPECT_EQ(binding.rebinds(), 0u);
  EXPECT_EQ(binding.Refusal("sample", "polarimeter"),
            "sample from participant 01000000.00000000.00000002 refused: the bench's polarimeter is "
            "01000000.00000000.00000001 (399 refused so far)");
}

TEST(SourceBindingTest, ASilentSourceIsReplacedAfterTheReleaseTimeNotBefore) {
  SourceBinding binding(100 * kMs);
  ASSERT_TRUE(binding.Accept(Source(1), 0));
  EXPECT_FALSE(binding.Accept(Source(2), 100 * kMs));  // exactly the release time: not yet
  EXPECT_TRUE(binding.Accept(Source(2), 100 * kMs + 1));
  EXPECT_EQ(binding.source(), Source(2));
  EXPECT_EQ(binding.rebinds(), 1u);
  // The old source is now the foreign one.
  EXPECT_FALSE(binding.Accept(Source(1), 101 * kMs));
  EXPECT_EQ(binding.refused(), 2u);
}

TEST(SourceBindingTest, RefusedMessagesDoNotKeepTheBindingAliveNorTakeIt) {
  SourceBinding binding(100 * kMs);
  ASSERT_TRUE(binding.Accept(Source(1), 0));
  // A forger talking all the time does not extend the bound source's silence...
  for (int64_t t = kMs; t <= 100 * kMs; t += kMs) EXPECT_FALSE(binding.Accept(Source(2), t));
  // ...and the bound source that speaks again in time keeps its binding.
  EXPECT_TRUE(binding.Accept(Source(1), 100 * kMs));
  EXPECT_FALSE(binding.Accept(Source(2), 150 * kMs));
  EXPECT_EQ(binding.source(), Source(1));
}

TEST(SourceBindingTest, ASourceThatLeftIsReplacedAtOnceAndOnlyIt) {
  SourceBinding binding(100 * kMs);
  std::vector<SourceId> asked;
  bool left = false;
  const auto has_left = [&](const SourceId& source) {
    asked.push_back(source);
    return left;
  };
  ASSERT_TRUE(binding.Accept(Source(1), 0, has_left));
  EXPECT_TRUE(asked.empty()) << "nothing to ask while nothing is refused";
  // Still there: another source is refused, whatever it sends, and the test is of the bound one.
  EXPECT_FALSE(binding.Accept(Source(2), kMs, has_left));
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], Source(1));
  // Gone (its participant deleted): the next source is taken without waiting the release time.
  left = true;
  EXPECT_TRUE(binding.Accept(Source(2), 2 * kMs, has_left));
  EXPECT_EQ(binding.source(), Source(2));
  EXPECT_EQ(binding.rebinds(), 1u);
  EXPECT_EQ(binding.refused(), 1u);
  // The bound source itself is never asked about, nor is a message of it refused.
  asked.clear();
  EXPECT_TRUE(binding.Accept(Source(2), 3 * kMs, has_left));
  EXPECT_TRUE(asked.empty());
  // Release() alone: the next source is taken, counted as a rebind.
  binding.Release();
  EXPECT_FALSE(binding.bound());
  EXPECT_TRUE(binding.Accept(Source(3), 4 * kMs));
  EXPECT_EQ(binding.rebinds(), 2u);
}

TEST(SourceBindingTest, SourceNamesAreTheGuidPrefixInHex) {
  EXPECT_EQ(SourceName(Source(0xab)), "01000000.00000000.000000ab");
}

}  // namespace
}  // namespace dpc
