// The monitor's line as a person reads it: the loop's condition first, with how long it has
// held; on a terminal of 80 or 100 columns the line fits (the least important fields go first,
// a long holding reason is cut), in a pipe every field is there.
#include "monitor_command.h"

#include <gtest/gtest.h>

#include <string>

namespace dpc::tools {
namespace {

msg::Target PointTarget() {
  msg::Target t;
  t.bench_id("bench1");
  t.revision((uint64_t{7} << 32) | 2);
  t.kind(msg::TARGET_POINT);
  t.point({0.0, 0.6, 0.8});
  return t;
}

msg::StokesSample Sample(double s1, double s2, double s3) {
  msg::StokesSample s;
  s.bench_id("bench1");
  s.s_in({1.0, 0.0, 0.0});
  s.s_out({s1, s2, s3});
  return s;
}

msg::WaveplateState State(bool active, const std::string& reason = "") {
  msg::WaveplateState s;
  s.bench_id("bench1");
  s.mode(active ? msg::DRIVER_ACTIVE : msg::DRIVER_HOLDING);
  s.reason(reason);
  s.obeyed_controller_id(active ? "main" : "");
  s.obeyed_priority(10);
  s.phi_applied({0.123, -0.456, 0.789, 1.5});
  return s;
}

msg::ControllerStatus Status(const std::string& id, uint64_t missed) {
  msg::ControllerStatus s;
  s.bench_id("bench1");
  s.controller_id(id);
  s.missed_deadlines(missed);
  return s;
}

/// A bench with four stages, three controllers, locked on the target.
MonitorState LockedBench() {
  MonitorState state(10.0);
  state.OnTarget(PointTarget());
  state.OnState(State(true));
  for (const char* id : {"main", "standby", "experimental-gp"}) state.OnStatus(Status(id, 12));
  return state;
}

TEST(MonitorStateTest, TheFullLineStartsWithTheConditionAndKeepsEveryField) {
  MonitorState state(10.0);
  EXPECT_EQ(state.TakeLine(0.2).rfind("WAITING | error_deg - (no target yet) | phi - |", 0), 0u);
  state = LockedBench();
  state.OnSample(Sample(0.0, 0.6, 0.8));
  const std::string line = state.TakeLine(0.2);
  EXPECT_EQ(line.rfind("LOCKED 0.0 s | error_deg 0.000 (max 0.000) | phi [+0.123, -0.456, +0.789, +1.500] | rate_hz 5.0 | "
                       "ACTIVE obeyed main (priority 10) | missed_deadlines experimental-gp=12 main=12 standby=12 | "
                       "target r2",
                       0),
            0u)
      << line;
}

TEST(MonitorStateTest, TheConditionSaysHowLongItHasHeld) {
  MonitorState state = LockedBench();
  for (int i = 0; i < 3; ++i) {
    state.OnSample(Sample(0.0, 0.6, 0.8));
    state.TakeLine(0.5);
  }
  state.OnSample(Sample(0.0, 0.6, 0.8));
  EXPECT_EQ(state.TakeLine(0.5, 80).rfind("LOCKED 1.5 s | ", 0), 0u);
  // 90° away: lost, from now on.
  state.OnSample(Sample(1.0, 0.0, 0.0));
  EXPECT_EQ(state.TakeLine(0.5, 80).rfind("LOST 0.0 s | error 90.00° max 90.00°", 0), 0u);
  state.OnSample(Sample(1.0, 0.0, 0.0));
  EXPECT_EQ(state.TakeLine(0.5, 80).rfind("LOST 0.5 s | ", 0), 0u);
  // The polarimeter stops.
  EXPECT_EQ(state.TakeLine(0.5, 80).rfind("NO SAMPLES 0.0 s", 0), 0u);
}

TEST(MonitorStateTest, AtEightyAndAHundredColumnsTheLineFitsAndKeepsWhatMattersMost) {
  for (int width : {80, 100}) {
    MonitorState state = LockedBench();
    state.OnSample(Sample(0.0, 0.6, 0.8));
    const std::string line = state.TakeLine(0.2, width);
    EXPECT_LE(DisplayWidth(line), static_cast<size_t>(width)) << line;
    EXPECT_EQ(line.rfind("LOCKED 0.0 s | error 0.00° max 0.00° | obeys main (p10) | 5 Hz", 0), 0u) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos);
  }
  // 100 columns show more than 80: φ, then the target's revision.
  MonitorState wide = LockedBench();
  wide.OnSample(Sample(0.0, 0.6, 0.8));
  const std::string line = wide.TakeLine(0.2, 100);
  EXPECT_NE(line.find("φ [+0.123, -0.456, +0.789, +1.500]"), std::string::npos) << line;
  MonitorState narrow = LockedBench();
  narrow.OnSample(Sample(0.0, 0.6, 0.8));
  EXPECT_EQ(narrow.TakeLine(0.2, 40), "LOCKED 0.0 s | error 0.00° max 0.00°");
}

TEST(MonitorStateTest, HoldingKeepsOneLineWithTheReasonCutToTheRoomLeft) {
  const std::string reason(230, 'r');  // the driver's longest reasons are about this long
  for (int width : {80, 100}) {
    MonitorState state = LockedBench();
    state.OnState(State(false, "main silent for 1.73 ms and no other controller answered newer samples; " + reason));
    state.OnSample(Sample(0.0, 0.6, 0.8));
    const std::string line = state.TakeLine(0.2, width);
    EXPECT_EQ(DisplayWidth(line), static_cast<size_t>(width)) << line;
    EXPECT_EQ(line.rfind("HOLDING 0.0 s | error 0.00° max 0.00° | ", 0), 0u) << line;
    EXPECT_NE(line.find("| main silent for 1.73 ms"), std::string::npos) << line;
    EXPECT_EQ(line.substr(line.size() - 3), "…") << line;
  }
}

TEST(DisplayWidthTest, CountsCodePointsNotBytes) {
  EXPECT_EQ(DisplayWidth(""), 0u);
  EXPECT_EQ(DisplayWidth("abc"), 3u);
  EXPECT_EQ(DisplayWidth("φ 1.0°"), 6u);
  EXPECT_EQ(DisplayWidth("…"), 1u);
}

}  // namespace
}  // namespace dpc::tools
