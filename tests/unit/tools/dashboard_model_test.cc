// What the dashboard's page is sent: the loop's condition, the period's error and extinction,
// a bounded trail whatever the rate, the target with its revision exact, the driver and the
// controllers.
#include "dashboard_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>

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

BenchSample Sample(uint64_t sequence, const StokesVector& s_out) {
  BenchSample s;
  s.sequence = sequence;
  s.s_in = StokesVector(1.0, 0.0, 0.0);
  s.s_out = s_out;
  return s;
}

/// The unit vector at `angle_deg` from [0, 0.6, 0.8], turned towards S1.
StokesVector AtAngleFromTarget(double angle_deg) {
  const double a = angle_deg * std::numbers::pi / 180.0;
  return StokesVector(std::sin(a), 0.6 * std::cos(a), 0.8 * std::cos(a));
}

DriverState State(DriverMode mode, int64_t sample_publish_ns, int64_t publish_ns, uint64_t answers) {
  DriverState s;
  s.mode = mode;
  s.reason = mode == DriverMode::kActive ? "obeying main (priority 10)" : "no controller";
  s.obeyed_controller_id = mode == DriverMode::kActive ? "main" : "";
  s.answers_sample = answers;
  s.sample_publish_time_ns = sample_publish_ns;
  s.publish_time_ns = publish_ns;
  s.motion.phi = ControlVector::Zero(3);
  s.motion.phi << 0.1, -0.2, 0.3;
  s.motion.rate_per_s = ControlVector::Zero(3);
  s.saturated[1] = true;
  return s;
}

TEST(ExtinctionTest, IsTwentyLogTangentOfHalfTheAngle) {
  EXPECT_NEAR(ExtinctionDb(90.0), 0.0, 1e-12);  // halfway: as much passed as rejected
  EXPECT_NEAR(ExtinctionDb(1.0), 20.0 * std::log10(std::tan(0.5 * std::numbers::pi / 180.0)), 1e-12);  // −41.2 dB
  EXPECT_DOUBLE_EQ(ExtinctionDb(0.0), -80.0);   // the floor, not −∞
  EXPECT_GT(ExtinctionDb(180.0), 100.0);        // orthogonal: finite, huge
}

TEST(DashboardModelTest, SaysWaitingUntilSamplesAndATargetArriveThenLockedOrLost) {
  DashboardModel model(DashboardModelOptions{10.0});
  EXPECT_EQ(model.TakeSnapshot(0.0)["condition"], "WAITING");
  model.OnTarget(PointTarget((uint64_t{1700000000} << 32) | 1));
  model.OnSample(Sample(1, AtAngleFromTarget(2.0)));
  model.OnSample(Sample(2, AtAngleFromTarget(4.0)));
  const auto locked = model.TakeSnapshot(0.05);
  EXPECT_EQ(locked["condition"], "LOCKED");
  EXPECT_NEAR(locked["error_deg"]["mean"].get<double>(), 3.0, 1e-9);
  EXPECT_NEAR(locked["error_deg"]["max"].get<double>(), 4.0, 1e-9);
  EXPECT_NEAR(locked["extinction_db"].get<double>(), ExtinctionDb(3.0), 1e-12);
  EXPECT_NEAR(locked["samples"]["rate_hz"].get<double>(), 40.0, 1e-9);

  model.OnSample(Sample(3, AtAngleFromTarget(30.0)));
  const auto lost = model.TakeSnapshot(0.10);
  EXPECT_EQ(lost["condition"], "LOST");
  EXPECT_DOUBLE_EQ(lost["condition_for_s"].get<double>(), 0.0);
  model.OnSample(Sample(4, AtAngleFromTarget(31.0)));
  EXPECT_NEAR(model.TakeSnapshot(0.25)["condition_for_s"].get<double>(), 0.15, 1e-12);  // since it began

  // No sample in a period: the bench stopped.
  EXPECT_EQ(model.TakeSnapshot(0.30)["condition"], "NO SAMPLES");
  // The driver holds: that is what the page says, whatever the error.
  model.OnState(State(DriverMode::kHolding, 0, 0, 0));
  model.OnSample(Sample(5, AtAngleFromTarget(1.0)));
  EXPECT_EQ(model.TakeSnapshot(0.35)["condition"], "HOLDING");
}

TEST(DashboardModelTest, TheTrailStaysBoundedWhateverTheRateAndSpansThePeriod) {
  DashboardModel model(DashboardModelOptions{10.0, 48});
  for (int period = 1; period <= 3; ++period) {
    for (uint64_t i = 1; i <= 10000; ++i) model.OnSample(Sample(i, AtAngleFromTarget(static_cast<double>(i) * 0.01)));
    const auto snapshot = model.TakeSnapshot(0.05 * period);
    const auto& trail = snapshot["trail"]["s_out"];
    EXPECT_LE(trail.size(), 48u);
    EXPECT_GE(trail.size(), 24u);
    EXPECT_EQ(snapshot["trail"]["s_in"].size(), trail.size());
    // The first point is the period's first sample (≈ 0°), the last one from its end.
    const StokesVector last(trail.back()[0].get<double>(), trail.back()[1].get<double>(), trail.back()[2].get<double>());
    EXPECT_GT(last.x(), std::sin(60.0 * std::numbers::pi / 180.0));
  }
  // A slow bench afterwards: every sample is shown again once the stride relaxes.
  for (int period = 0; period < 12; ++period) {
    for (uint64_t i = 1; i <= 5; ++i) model.OnSample(Sample(i, AtAngleFromTarget(1.0)));
    model.TakeSnapshot(1.0 + period);
  }
  for (uint64_t i = 1; i <= 5; ++i) model.OnSample(Sample(i, AtAngleFromTarget(1.0)));
  EXPECT_EQ(model.TakeSnapshot(20.0)["trail"]["s_out"].size(), 5u);
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

TEST(DashboardModelTest, LoopLatencyPercentilesComeFromEachNewlyAnsweredSample) {
  DashboardModel model;
  for (uint64_t i = 1; i <= 100; ++i) {
    const int64_t published = 1'000'000'000 + static_cast<int64_t>(i) * 1'000'000;
    model.OnState(State(DriverMode::kActive, published, published + static_cast<int64_t>(i) * 1000, i));
    model.OnState(State(DriverMode::kActive, published, published + 999'000'000, i));  // a heartbeat: not counted
  }
  const auto snapshot = model.TakeSnapshot(1.0);
  EXPECT_DOUBLE_EQ(snapshot["loop_latency_us"]["p50"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(snapshot["loop_latency_us"]["p99"].get<double>(), 99.0);
  EXPECT_DOUBLE_EQ(snapshot["loop_latency_us"]["max"].get<double>(), 100.0);
  EXPECT_TRUE(model.TakeSnapshot(2.0)["loop_latency_us"].is_null());  // a new period
}

TEST(DashboardModelTest, DriverAndControllersAreShownAndTheObeyedOneMarked) {
  DashboardModel model;
  model.OnState(State(DriverMode::kActive, 0, 0, 0));
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
  model.OnRefused("dpc_stokes_sample", "s_out: |S| = 2");
  const auto snapshot = model.TakeSnapshot(1.0);
  EXPECT_EQ(snapshot["driver"]["mode"], "ACTIVE");
  EXPECT_EQ(snapshot["driver"]["phi"].size(), 3u);
  EXPECT_EQ(snapshot["driver"]["saturated"][1], true);
  ASSERT_EQ(snapshot["controllers"].size(), 2u);
  EXPECT_EQ(snapshot["controllers"][0]["id"], "main");
  EXPECT_EQ(snapshot["controllers"][0]["obeyed"], true);
  EXPECT_EQ(snapshot["controllers"][1]["obeyed"], false);
  EXPECT_NEAR(snapshot["controllers"][1]["silent_s"].get<double>(), 0.8, 1e-12);
  EXPECT_NEAR(snapshot["controllers"][0]["compute_mean_us"].get<double>(), 1.5, 1e-9);
  EXPECT_EQ(snapshot["refused"]["by_topic"]["dpc_stokes_sample"], 1u);
}

TEST(DashboardModelTest, AtMostSixtyFourControllersAreKeptTheLongestSilentGoesFirst) {
  DashboardModel model;
  for (int i = 0; i < 100; ++i) {
    ControllerStatusReport s;
    s.controller_id = "c" + std::to_string(i);
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
