#include "target_authority.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace dpc::services {
namespace {

constexpr uint64_t kEpoch = 1'700'000'000;
constexpr uint64_t kFirst = kEpoch << 32 | 1;

TEST(TargetAuthorityTest, TheScenariosTargetIsTheEpochsFirstRevisionAndEveryAcceptedChangeTheNext) {
  TargetAuthority authority(TargetConfig{}, kEpoch);
  EXPECT_EQ(authority.current().revision, kFirst);
  EXPECT_EQ(authority.current().request_id, "");
  TargetConfig linear;
  linear.kind = TargetConfig::Kind::kSet;
  const TargetAuthority::Reply reply = authority.Request("r1", linear);
  EXPECT_TRUE(reply.accepted);
  EXPECT_EQ(reply.revision, kFirst + 1);
  EXPECT_EQ(reply.message, fmt::format("target revision {}", kFirst + 1));
  EXPECT_EQ(authority.current().revision, kFirst + 1);
  EXPECT_EQ(authority.current().request_id, "r1");
  EXPECT_EQ(authority.current().target.kind, TargetConfig::Kind::kSet);
}

TEST(TargetAuthorityTest, ARestartedDriversRevisionsAreAboveEveryOneBefore) {
  TargetAuthority before(TargetConfig{}, kEpoch);
  for (int k = 0; k < 1000; ++k) before.Request("r", TargetConfig{});
  const TargetAuthority after(TargetConfig{}, kEpoch + 1);  // a second later
  EXPECT_GT(after.current().revision, before.current().revision);
  EXPECT_GE(TargetAuthority::EpochNow(), 1'700'000'000u);
}

TEST(TargetAuthorityTest, AnInvalidTargetIsRefusedAndChangesNothing) {
  TargetAuthority authority(TargetConfig{}, kEpoch);
  TargetConfig off_sphere;
  off_sphere.point = StokesVector(0.0, 0.0, 2.0);
  const TargetAuthority::Reply reply = authority.Request("r1", off_sphere);
  EXPECT_FALSE(reply.accepted);
  EXPECT_EQ(reply.revision, kFirst);
  EXPECT_NE(reply.message.find("target.point"), std::string::npos) << reply.message;
  EXPECT_EQ(authority.current().revision, kFirst);
  EXPECT_FALSE(authority.Refuse("r2", "target.kind: unknown target kind 7").accepted);
  EXPECT_EQ(authority.current().revision, kFirst);
}

}  // namespace
}  // namespace dpc::services
