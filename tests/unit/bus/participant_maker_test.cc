// When a secured reload moves the endpoints to the new participant: once it has authenticated
// every peer the running one had (other than itself), and not before.
#include "dpc/bus/participant_maker.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace dpc::bus {
namespace {

TEST(PeersNotYetAuthenticatedTest, CountsThePeersOfTheRunningParticipantTheNewOneHasNotAuthenticated) {
  size_t peers = 0;
  // The running participant authenticated the driver, the polarimeter and the new participant.
  const std::vector<std::string> running = {"d.1", "p.1", "new"};
  EXPECT_EQ(PeersNotYetAuthenticated(running, {}, "new", &peers), 2u);
  EXPECT_EQ(peers, 2u) << "the new participant is no peer to wait for";
  std::vector<std::string> names;
  EXPECT_EQ(PeersNotYetAuthenticated(running, {"old", "p.1"}, "new", &peers, &names), 1u);
  EXPECT_EQ(names, std::vector<std::string>{"d.1"});
  EXPECT_EQ(PeersNotYetAuthenticated(running, {"p.1", "old", "d.1"}, "new", &peers), 0u);
  // A peer only the new one knows (a newcomer, the old participant) does not matter.
  EXPECT_EQ(PeersNotYetAuthenticated(running, {"p.1", "d.1", "x.9"}, "new", &peers), 0u);
  // Alone on the bench: nothing to wait for.
  EXPECT_EQ(PeersNotYetAuthenticated({"new"}, {}, "new", &peers), 0u);
  EXPECT_EQ(peers, 0u);
}

}  // namespace
}  // namespace dpc::bus
