#include "sample_timeline.h"

#include <gtest/gtest.h>

#include <limits>

namespace dpc::services {
namespace {

constexpr int64_t kUs = 1000;

TEST(SampleTimeline, KnowsNothingBeforeTheFirstSample) {
  SampleTimeline timeline;
  EXPECT_EQ(timeline.newest(), 0u);
  EXPECT_FALSE(timeline.Find(1).has_value());
  EXPECT_EQ(timeline.CheckAnswer(1, 0), "");  // may still be on its way
  EXPECT_NE(timeline.CheckAnswer(100, 0).find("no sample of the bench has arrived yet"), std::string::npos);
  EXPECT_NE(timeline.CheckAnswer(0, 0).find("answers no sample"), std::string::npos);
}

TEST(SampleTimeline, RecordsTheLatestSamplesAndRefusesWhatContradictsThem) {
  SampleTimeline timeline;
  for (uint64_t k = 1; k <= 2000; ++k) timeline.OnSample(k, static_cast<int64_t>(k - 1) * 100 * kUs, 7);
  EXPECT_EQ(timeline.newest(), 2000u);
  ASSERT_TRUE(timeline.Find(2000).has_value());
  EXPECT_EQ(timeline.Find(2000)->time_ns, 1999 * 100 * kUs);
  EXPECT_EQ(timeline.Find(1500)->publish_time_ns, 7);
  EXPECT_FALSE(timeline.Find(2000 - SampleTimeline::kCapacity).has_value()) << "overwritten";
  EXPECT_EQ(timeline.CheckAnswer(1500, 1499 * 100 * kUs), "");
  EXPECT_NE(timeline.CheckAnswer(1500, 4'000'000'000'000'000'000).find("is not the time of sample 1500"),
            std::string::npos);
  EXPECT_EQ(timeline.CheckAnswer(2000 + SampleTimeline::kMaxLead, 0), "");
  EXPECT_NE(timeline.CheckAnswer(2001 + SampleTimeline::kMaxLead, 0).find("newest sample is 2000"),
            std::string::npos);
  EXPECT_NE(timeline.CheckAnswer(std::numeric_limits<uint64_t>::max(), 0).find("newest sample is 2000"),
            std::string::npos);
}

TEST(SampleTimeline, PlacesASampleItHasNotSeenAtTheBenchsPeriod) {
  SampleTimeline timeline;
  timeline.OnSample(10, 900 * kUs, 0);
  timeline.OnSample(11, 1000 * kUs, 0);
  EXPECT_EQ(timeline.TimeOfNs(11), 1000 * kUs);
  EXPECT_EQ(timeline.TimeOfNs(12), 1100 * kUs);  // still on its way
  EXPECT_EQ(timeline.TimeOfNs(5), 400 * kUs);    // lost (never recorded)
  // Saturated, never overflowing.
  EXPECT_EQ(timeline.TimeOfNs(std::numeric_limits<uint64_t>::max()), std::numeric_limits<int64_t>::max());
}

TEST(SampleTimeline, AnEarlierNumberIsANewBenchRunTheNewestAgainIsNot) {
  SampleTimeline timeline;
  for (uint64_t k = 1; k <= 50; ++k) EXPECT_FALSE(timeline.OnSample(k, static_cast<int64_t>(k) * kUs, 0));
  EXPECT_FALSE(timeline.OnSample(50, 50 * kUs, 0)) << "a lockstep bench re-publishes its newest sample";
  EXPECT_TRUE(timeline.OnSample(1, kUs, 0)) << "numbering from 1 again";
  EXPECT_EQ(timeline.newest(), 1u);
  EXPECT_FALSE(timeline.Find(50).has_value());
  EXPECT_TRUE(timeline.OnSample(1, 5 * kUs, 0)) << "the newest number at another time";
  // A sample numbered near 2^64 (a foreign writer) costs one restart, nothing more.
  EXPECT_FALSE(timeline.OnSample(std::numeric_limits<uint64_t>::max(), std::numeric_limits<int64_t>::min(), 0));
  EXPECT_TRUE(timeline.OnSample(2, 2 * kUs, 0));
  EXPECT_FALSE(timeline.OnSample(3, 3 * kUs, 0));
  EXPECT_EQ(timeline.TimeOfNs(4), 4 * kUs);
}

}  // namespace
}  // namespace dpc::services
