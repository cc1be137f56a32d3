// What the dashboard's page is sent: the loop's condition, the period's error and extinction
// from the bench's summaries, the target with its revision exact, the driver and the controllers.
#include "dashboard_model.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>

#include "dashboard_command.h"

namespace dpc::tools {
namespace {

BenchTarget PointTarget(uint64_t revision) {
  BenchTarget t;
  t.revision = revision;
  t.target.kind = TargetConfig::Kind::kPoint;
  t.target.point = StokesVector(0.0, 0.6, 0.8);
  return t;
}

/// A summary of `samples` samples over 50 ms with this mean and largest error.
BenchSummary Summary(uint64_t sequence, uint64_t samples, std::optional<double> error_mean_deg, double error_max_deg = 0,
                     std::optional<DriverMode> mode = DriverMode::kActive) {
  BenchSummary s;
  s.sequence = sequence;
  s.publish_time_ns = static_cast<int64_t>(sequence) * 50'000'000;
  s.period_s = 0.05;
  s.samples = samples;
  s.last_sample = sequence * samples;
  s.s_in = StokesVector(1.0, 0.0, 0.0);
  s.s_out = StokesVector(0.0, 0.6, 0.8);
  s.trail = {{1, 0, 0, 0, 0.6, 0.8}, {0, 1, 0, 0, 0.6, 0.8}};
  s.error_mean_deg = error_mean_deg;
  s.error_max_deg = error_max_deg;
  s.latencies = samples;
  s.latency_p50_us = 200;
  s.latency_p99_us = 900;
  if (mode) {
    DriverState state;
    state.mode = *mode;
    state.reason = *mode == DriverMode::kActive ? "obeying main (priority 10)" : "no controller";
    state.obeyed_controller_id = *mode == DriverMode::kActive ? "main" : "";
    state.motion = WaveplateMotion::Still(ControlVector::Zero(3));
    state.motion.phi << 0.1, -0.2, 0.3;
    state.saturated[1] = true;
    s.state = state;
  }
  return s;
}

TEST(ExtinctionTest, IsTwentyLogTangentOfHalfTheAngle) {
  EXPECT_NEAR(ExtinctionDb(90.0), 0.0, 1e-12);  // halfway: as much passed as rejected
  EXPECT_NEAR(ExtinctionDb(1.0), 20.0 * std::log10(std::tan(0.5 * std::numbers::pi / 180.0)), 1e-12);  // −41.2 dB
  EXPECT_DOUBLE_EQ(ExtinctionDb(0.0), -80.0);   // the floor, not −∞
  EXPECT_GT(ExtinctionDb(180.0), 100.0);        // orthogonal: finite, huge
}

TEST(DashboardModelTest, SaysWaitingThenLockedOrLostFromTheSummariesOfThePeriod) {
  DashboardModel model(DashboardModelOptions{10.0, 1.0});
  EXPECT_EQ(model.TakeSnapshot(0.0)["condition"], "WAITING");
  // Two summaries in one push period: their errors weighted by their samples.
  model.OnSummary(Summary(1, 100, 2.0, 4.0), 0.01);
  model.OnSummary(Summary(2, 300, 6.0, 9.0), 0.06);
  const auto locked = model.TakeSnapshot(0.1);
  EXPECT_EQ(locked["condition"], "LOCKED");
  EXPECT_EQ(locked["fresh"], true);
  EXPECT_NEAR(locked["error_deg"]["mean"].get<double>(), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(locked["error_deg"]["max"].get<double>(), 9.0);
  EXPECT_NEAR(locked["extinction_db"].get<double>(), ExtinctionDb(5.0), 1e-12);
  EXPECT_NEAR(locked["samples"]["rate_hz"].get<double>(), 4000.0, 1e-9);  // 400 samples in 2 × 50 ms
  EXPECT_EQ(locked["trail"]["s_out"].size(), 4u);
  EXPECT_DOUBLE_EQ(locked["loop_latency_us"]["p99"].get<double>(), 900.0);

  // A push with no new summary repeats the figures, not fresh (the page plots nothing new).
  const auto repeated = model.TakeSnapshot(0.15);
  EXPECT_EQ(repeated["fresh"], false);
  EXPECT_EQ(repeated["condition"], "LOCKED");
  EXPECT_EQ(repeated["trail"]["s_out"].size(), 0u);

  model.OnSummary(Summary(3, 200, 30.0, 40.0), 0.2);
  const auto lost = model.TakeSnapshot(0.2);
  EXPECT_EQ(lost["condition"], "LOST");
  EXPECT_DOUBLE_EQ(lost["condition_for_s"].get<double>(), 0.0);
  model.OnSummary(Summary(4, 200, 31.0, 40.0), 0.3);
  EXPECT_NEAR(model.TakeSnapshot(0.35)["condition_for_s"].get<double>(), 0.15, 1e-12);  // since it began

  // No summary for longer than stale_s: the bench stopped; no figures are shown as current.
  const auto stopped = model.TakeSnapshot(1.5);
  EXPECT_EQ(stopped["condition"], "NO SAMPLES");
  EXPECT_TRUE(stopped["error_deg"].is_null());
  EXPECT_DOUBLE_EQ(stopped["samples"]["rate_hz"].get<double>(), 0.0);
  // It comes back, with the driver holding: that is what the page says, whatever the error.
  model.OnSummary(Summary(5, 100, 1.0, 2.0, DriverMode::kHolding), 1.6);
  EXPECT_EQ(model.TakeSnapshot(1.6)["condition"], "HOLDING");
}

TEST(DashboardModelTest, AnOldSummaryArrivingLateChangesNothing) {
  DashboardModel model;
  model.OnSummary(Summary(5, 100, 2.0, 3.0), 0.0);
  model.OnSummary(Summary(4, 100, 50.0, 60.0), 0.01);
  EXPECT_NEAR(model.TakeSnapshot(0.05)["error_deg"]["mean"].get<double>(), 2.0, 1e-12);
}

TEST(DashboardModelTest, TheRevisionIsSentExactlyAsTextBecauseItExceedsAJavaScriptNumber) {
  DashboardModel model;
  const uint64_t revision = (uint64_t{1764000000} << 32) | 3;  // > 2^53
  model.OnTarget(PointTarget(revision));
  model.OnTarget(PointTarget(revision - 1));  // an older one arriving late changes nothing
  const auto snapshot = model.TakeSnapshot(1.0);
  EXPECT_EQ(snapshot["target"]["revision"], std::to_string(revision));
  EXPECT_EQ(snapshot["target"]["revision_count"], 3u);
  EXPECT_EQ(snapshot["target"]["revision_epoch"], 1764000000u);
  EXPECT_EQ(snapshot["target"]["kind"], "point");
}

TEST(DashboardModelTest, ASetTargetIsSentNormalized) {
  DashboardModel model;
  BenchTarget t;
  t.revision = 5;
  t.target.kind = TargetConfig::Kind::kSet;
  t.target.normal = Vector3(0.0, 0.0, 2.0);
  t.target.offset = 0.5;  // n·S = c with |n| = 2: the plane S3 = 0.25
  model.OnTarget(t);
  const auto target = model.TakeSnapshot(1.0)["target"];
  EXPECT_EQ(target["kind"], "set");
  EXPECT_DOUBLE_EQ(target["normal"][2].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(target["offset"].get<double>(), 0.25);
}

TEST(DashboardModelTest, DriverAndControllersAreShownAndTheObeyedOneMarked) {
  DashboardModel model;
  model.OnSummary(Summary(1, 10, 1.0, 1.0), 0.0);
  ControllerStatusReport main;
  main.controller_id = "main";
  main.priority = 10;
  main.law = "gp";
  main.sigma_min = 0.5;
  main.compute_time_mean_s = 1.5e-6;
  ControllerStatusReport standby = main;
  standby.controller_id = "standby";
  model.OnStatus(main, 0.5);
  model.OnStatus(standby, 0.2);
  model.OnRefused("dpc_bench_summary", "s_out: |S| = 2");
  const auto snapshot = model.TakeSnapshot(1.0);
  EXPECT_EQ(snapshot["driver"]["mode"], "ACTIVE");
  EXPECT_EQ(snapshot["driver"]["phi"].size(), 3u);
  EXPECT_DOUBLE_EQ(snapshot["driver"]["phi"][1].get<double>(), -0.2);
  EXPECT_EQ(snapshot["driver"]["saturated"][1], true);
  ASSERT_EQ(snapshot["controllers"].size(), 2u);
  EXPECT_EQ(snapshot["controllers"][0]["id"], "main");
  EXPECT_EQ(snapshot["controllers"][0]["obeyed"], true);
  EXPECT_EQ(snapshot["controllers"][1]["obeyed"], false);
  EXPECT_NEAR(snapshot["controllers"][1]["silent_s"].get<double>(), 0.8, 1e-12);
  EXPECT_NEAR(snapshot["controllers"][0]["compute_mean_us"].get<double>(), 1.5, 1e-9);
  EXPECT_EQ(snapshot["refused"]["by_topic"]["dpc_bench_summary"], 1u);
}

TEST(DashboardModelTest, AtMostSixtyFourControllersAreKeptTheLongestSilentGoesFirst) {
  DashboardModel model;
  for (int i = 0; i < 100; ++i) {
    ControllerStatusReport s;
    s.controller_id = fmt::format("c{}", i);
    model.OnStatus(s, static_cast<double>(i));
  }
  const auto controllers = model.TakeSnapshot(100.0)["controllers"];
  EXPECT_EQ(controllers.size(), 64u);
  for (const auto& c : controllers) EXPECT_GE(std::stoi(c["id"].get<std::string>().substr(1)), 36);
}

// ---- a page's request to set the target: untrusted input

TEST(PageTargetRequestTest, APointASetAndAnyLinearSopAreRead) {
  std::string tag, error;
  auto point = ParsePageTargetRequest(R"({"type":"set_target","tag":"page-1","kind":"point","point":[0.6,0,0.8]})",
                                      &tag, &error);
  ASSERT_TRUE(point) << error;
  EXPECT_EQ(tag, "page-1");
  EXPECT_EQ(point->kind, TargetConfig::Kind::kPoint);
  EXPECT_DOUBLE_EQ(point->point.x(), 0.6);
  auto set = ParsePageTargetRequest(R"({"type":"set_target","kind":"set","normal":[0,0,1],"offset":0.3})", &tag, &error);
  ASSERT_TRUE(set) << error;
  EXPECT_DOUBLE_EQ(set->offset, 0.3);
  auto linear = ParsePageTargetRequest(R"({"type":"set_target","kind":"linear"})", &tag, &error);
  ASSERT_TRUE(linear) << error;
  EXPECT_EQ(linear->kind, TargetConfig::Kind::kSet);
  EXPECT_DOUBLE_EQ(linear->normal.z(), 1.0);
}

TEST(PageTargetRequestTest, EverythingElseIsRefusedWithTheReason) {
  const std::pair<const char*, const char*> cases[] = {
      {"not json", "not a JSON object"},
      {"[1,2,3]", "not a JSON object"},
      {R"({"type":"shutdown"})", "unknown request"},
      {R"({"type":"set_target","kind":"circle"})", "kind:"},
      {R"({"type":"set_target","kind":"point","point":[1,1,0]})", "point: [1, 1, 0] has |S| = 1.41421356"},
      {R"({"type":"set_target","kind":"point","point":[0.6,0]})", "point: give three numbers"},
      {R"({"type":"set_target","kind":"point","point":["0.6",0,0.8]})", "point: give three numbers"},
      {R"({"type":"set_target","kind":"point","point":[null,0,1]})", "point: give three numbers"},
      {R"({"type":"set_target","kind":"point","point":[1e999,0,0]})", "not a JSON object"},  // JSON has no Inf
      {R"({"type":"set_target","kind":"set","normal":[0,0,0]})", "normal"},
      {R"({"type":"set_target","kind":"set","normal":[0,0,1],"offset":"x"})", "offset: give a number"},
      {R"({"type":"set_target","kind":"set","normal":[0,0,1],"offset":1})", "offset"},
  };
  for (const auto& [text, expected] : cases) {
    std::string tag, error;
    EXPECT_FALSE(ParsePageTargetRequest(text, &tag, &error)) << text;
    EXPECT_NE(error.find(expected), std::string::npos) << text << " → " << error;
  }
}

TEST(PageTargetRequestTest, TheTagIsMadePrintableAndBounded) {
  std::string tag, error;
  ParsePageTargetRequest("{\"type\":\"set_target\",\"tag\":\"a\\nb\\u001b[31m" + std::string(200, 'x') + "\"}", &tag,
                         &error);
  EXPECT_EQ(tag.find('\n'), std::string::npos);
  EXPECT_EQ(tag.find('\x1b'), std::string::npos);
  EXPECT_LE(tag.size(), 64u + std::string("…").size());  // cut at 64 bytes, marked
}

}  // namespace
}  // namespace dpc::tools
