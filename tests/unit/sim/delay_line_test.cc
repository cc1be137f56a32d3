#include "dpc/sim/delay_line.h"

#include <gtest/gtest.h>

#include <deque>

namespace dpc {
namespace {

// Drives a DelayLine<int> like the simulator does and checks it against a plain FIFO: the
// command applied at sample k is the one issued at k − D (or the initial one), and a sample
// that issues nothing repeats the latest command.
TEST(DelayLineTest, AppliesEachCommandExactlyDelaySamplesLater) {
  for (int64_t delay : {1, 2, 5}) {
    DelayLine<int> line(delay, -1);
    std::deque<int> fifo(static_cast<size_t>(delay), -1);
    int latest = -1;
    int64_t slot = 0;
    for (int k = 0; k < 100; ++k, slot = line.Next(slot)) {
      ASSERT_EQ(line.at(slot), fifo.front()) << "delay " << delay << " sample " << k;
      fifo.pop_front();
      EXPECT_EQ(line.latest(), latest);
      const bool issue = k % 3 != 1;  // every third sample issues nothing
      if (issue) {
        line.issue(slot) = k;
        latest = k;
      }
      line.Close(slot, issue);
      fifo.push_back(latest);
    }
  }
}

TEST(DelayLineTest, NextWrapsAround) {
  DelayLine<double> line(3, 0.0);
  EXPECT_EQ(line.size(), 3);
  EXPECT_EQ(line.Next(0), 1);
  EXPECT_EQ(line.Next(2), 0);
}

}  // namespace
}  // namespace dpc
