#include "dpc/config/scenario_error.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <type_traits>

namespace dpc {
namespace {

TEST(ScenarioErrorTest, WhatJoinsLocationAndMessage) {
  const ScenarioError error("controller.step", "-0.1 is not > 0");
  EXPECT_EQ(error.location(), "controller.step");
  EXPECT_EQ(error.message(), "-0.1 is not > 0");
  EXPECT_STREQ(error.what(), "controller.step: -0.1 is not > 0");
}

TEST(ScenarioErrorTest, FilePositionsAreLocationsToo) {
  const ScenarioError error("scenarios/a.pbtxt:12:7", "Unknown field \"stpe\"");
  EXPECT_EQ(error.location(), "scenarios/a.pbtxt:12:7");
  EXPECT_STREQ(error.what(), "scenarios/a.pbtxt:12:7: Unknown field \"stpe\"");
}

TEST(ScenarioErrorTest, AnEmptyLocationLeavesTheMessageAlone) {
  const ScenarioError error("", "no location");
  EXPECT_EQ(error.location(), "");
  EXPECT_STREQ(error.what(), "no location");
}

TEST(ScenarioErrorTest, IsCaughtAsInvalidArgument) {
  EXPECT_THROW(throw ScenarioError("stages", "0 stages"), std::invalid_argument);
  try {
    throw ScenarioError("stages[1].map.table.angle_rad[3]", "2 after 3");
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "stages[1].map.table.angle_rad[3]: 2 after 3");
  }
}

TEST(ScenarioErrorTest, CopiesShareTheirParts) {
  const ScenarioError original("target.point", "not a unit vector");
  const ScenarioError copy = original;  // NOLINT(performance-unnecessary-copy-initialization)
  EXPECT_EQ(copy.location(), original.location());
  EXPECT_EQ(copy.message(), original.message());
  EXPECT_STREQ(copy.what(), original.what());
  static_assert(std::is_nothrow_copy_constructible_v<ScenarioError>);
}

}  // namespace
}  // namespace dpc
