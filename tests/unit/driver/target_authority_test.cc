#include "target_authority.h"

#include <gtest/gtest.h>

namespace dpc::services {
namespace {

TEST(TargetAuthorityTest, TheScenariosTargetIsRevisionOneAndEveryAcceptedChangeTheNext) {
  TargetAuthority authority(TargetConfig{});
  EXPECT_EQ(authority.current().revision, 1u);
  EXPECT_EQ(authority.current().request_id, "");
  TargetConfig linear;
  linear.kind = TargetConfig::Kind::kSet;
  const TargetAuthority::Reply reply = authority.Request("r1", linear);
  EXPECT_TRUE(reply.accepted);
  EXPECT_EQ(reply.revision, 2u);
  EXPECT_EQ(reply.message, "target revision 2");
  EXPECT_EQ(authority.current().revision, 2u);
  EXPECT_EQ(authority.current().request_id, "r1");
  EXPECT_EQ(authority.current().target.kind, TargetConfig::Kind::kSet);
}

TEST(TargetAuthorityTest, AnInvalidTargetIsRefusedAndChangesNothing) {
  TargetAuthority authority(TargetConfig{});
  TargetConfig off_sphere;
  off_sphere.point = StokesVector(0.0, 0.0, 2.0);
  const TargetAuthority::Reply reply = authority.Request("r1", off_sphere);
  EXPECT_FALSE(reply.accepted);
  EXPECT_EQ(reply.revision, 1u);
  EXPECT_NE(reply.message.find("target.point"), std::string::npos) << reply.message;
  EXPECT_EQ(authority.current().revision, 1u);
  EXPECT_FALSE(authority.Refuse("r2", "target.kind: unknown target kind 7").accepted);
  EXPECT_EQ(authority.current().revision, 1u);
}

}  // namespace
}  // namespace dpc::services
