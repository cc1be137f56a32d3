// The DDS tools' view of the bench's topics: names and aliases, enum names, every message as
// JSON (checked field by field against idl/dpc/bench.idl) and as one line of text.
#include "bus_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <regex>
#include <string>
#include <vector>

#include "support/process.h"

namespace dpc::tools {
namespace {

using Json = nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTolerance = 1e-15;

/// The field names of `struct name` in idl/dpc/bench.idl, in IDL order.
std::vector<std::string> IdlFields(const std::string& name) {
  const std::string idl = dpc::testing::Slurp(std::string(DPC_SOURCE_DIR) + "/idl/dpc/bench.idl");
  const size_t open = idl.find("struct " + name + " {");
  if (open == std::string::npos) return {};
  std::string body = idl.substr(open, idl.find("};", open) - open);
  body = body.substr(body.find('{') + 1);
  body = std::regex_replace(body, std::regex("//[^\n]*"), "");
  std::vector<std::string> fields;
  const std::regex last_name(R"(([A-Za-z_]\w*)\s*(\[\w+\])?\s*$)");
  size_t start = 0;
  for (size_t end; (end = body.find(';', start)) != std::string::npos; start = end + 1) {
    std::smatch match;
    const std::string declaration = body.substr(start, end - start);
    if (std::regex_search(declaration, match, last_name)) fields.push_back(match[1]);
  }
  return fields;
}

std::vector<std::string> Keys(const Json& object) {
  std::vector<std::string> keys;
  for (const auto& item : object.items()) keys.push_back(item.key());
  return keys;
}

bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(IdlFields, ReadsTheFieldsOfAStructInOrder) {
  EXPECT_EQ(IdlFields("ControlRange"), (std::vector<std::string>{"limited", "min_phi", "max_phi"}));
  EXPECT_EQ(IdlFields("StokesSample").size(), 9u);
}

TEST(BenchTopics, ListsTheNineTopicsInTheOrderOfTopicsH) {
  const auto& topics = BenchTopics();
  ASSERT_EQ(topics.size(), 9u);
  EXPECT_EQ(topics[8].name, "dpc_bench_summary");
  EXPECT_EQ(topics[8].alias, "summary");
  EXPECT_EQ(topics[0].name, "dpc_stokes_sample");
  EXPECT_EQ(topics[0].alias, "sample");
  EXPECT_EQ(topics[0].type_name, "dpc::msg::StokesSample");
  EXPECT_EQ(topics[2].name, "dpc_waveplate_state");
  EXPECT_EQ(topics[7].name, "dpc_target_reply");
  EXPECT_EQ(topics[7].alias, "reply");
}

TEST(ResolveTopic, AcceptsTheFullNameTheNameWithoutPrefixAndTheAlias) {
  for (const char* name : {"dpc_waveplate_state", "waveplate_state", "state"}) {
    const auto topic = ResolveTopic(name);
    ASSERT_TRUE(topic.has_value()) << name;
    EXPECT_EQ(topic->name, "dpc_waveplate_state") << name;
    EXPECT_EQ(topic->type_name, "dpc::msg::WaveplateState") << name;
  }
  EXPECT_EQ(ResolveTopic("target")->name, "dpc_target");
  EXPECT_EQ(ResolveTopic("target_request")->name, "dpc_target_request");
}

TEST(ResolveTopic, RefusesUnknownAndDifferentlyCasedNames) {
  EXPECT_FALSE(ResolveTopic("samples").has_value());
  EXPECT_FALSE(ResolveTopic("State").has_value());
  EXPECT_FALSE(ResolveTopic("").has_value());
  EXPECT_FALSE(ResolveTopic("dpc_").has_value());
}

TEST(DescribeValidTopics, NamesEveryTopicWithItsAlias) {
  const std::string text = DescribeValidTopics();
  EXPECT_EQ(text.rfind("dpc_stokes_sample (sample), dpc_waveplate_command (command), ", 0), 0u) << text;
  for (const BusTopic& topic : BenchTopics()) {
    EXPECT_TRUE(Contains(text, std::string(topic.name) + " (" + std::string(topic.alias) + ")")) << text;
  }
}

TEST(EnumNames, AreTheIdlNamesAndUnknownOutOfRange) {
  EXPECT_STREQ(DriverModeName(msg::DRIVER_ACTIVE), "DRIVER_ACTIVE");
  EXPECT_STREQ(DriverModeName(msg::DRIVER_HOLDING), "DRIVER_HOLDING");
  EXPECT_STREQ(DriverModeName(static_cast<msg::DriverMode>(7)), "UNKNOWN");
  EXPECT_STREQ(TargetKindName(msg::TARGET_POINT), "TARGET_POINT");
  EXPECT_STREQ(TargetKindName(msg::TARGET_SET), "TARGET_SET");
  EXPECT_STREQ(TargetKindName(static_cast<msg::TargetKind>(2)), "UNKNOWN");
  EXPECT_STREQ(ControlMapKindName(msg::MAP_LINEAR), "MAP_LINEAR");
  EXPECT_STREQ(ControlMapKindName(msg::MAP_POLYNOMIAL), "MAP_POLYNOMIAL");
  EXPECT_STREQ(ControlMapKindName(msg::MAP_TABLE), "MAP_TABLE");
  EXPECT_STREQ(ControlMapKindName(static_cast<msg::ControlMapKind>(3)), "UNKNOWN");
  EXPECT_STREQ(StageKindName(msg::STAGE_FIXED_AXIS), "STAGE_FIXED_AXIS");
  EXPECT_STREQ(StageKindName(msg::STAGE_ADJUSTABLE_AXIS), "STAGE_ADJUSTABLE_AXIS");
  EXPECT_STREQ(StageKindName(static_cast<msg::StageKind>(9)), "UNKNOWN");
}

TEST(FormatValues, WritesASignAndTheRequestedDecimals) {
  const double values[] = {0.0, 0.6, -0.8};
  EXPECT_EQ(FormatValues(values, 3), "[+0.0000, +0.6000, -0.8000]");
  EXPECT_EQ(FormatValues(values, 3, 2), "[+0.00, +0.60, -0.80]");
  EXPECT_EQ(FormatValues(values, 1, 0), "[+0]");
  EXPECT_EQ(FormatValues(values, 0), "[]");
}

TEST(StokesSampleMessage, JsonHasEveryFieldAndTextTheSample) {
  msg::StokesSample m;
  m.bench_id("b1");
  m.sequence_number(7);
  m.sample_time_ns(1'500'000);
  m.publish_time_ns(99);
  m.s_in({1.0, 0.0, 0.0});
  m.s_out({0.0, 0.6, 0.8});
  m.optical_power_known(false);
  m.optical_power_w(kNaN);
  m.lockstep(true);
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("StokesSample"));
  EXPECT_EQ(json["bench_id"], "b1");
  EXPECT_EQ(json["sequence_number"], 7u);
  EXPECT_EQ(json["sample_time_ns"], 1'500'000);
  EXPECT_NEAR(json["s_out"][2].get<double>(), 0.8, kTolerance);
  EXPECT_TRUE(json["optical_power_w"].is_null());
  EXPECT_EQ(json["lockstep"], true);
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "[b1] sample #7 t=0.001500 s")) << text;
  EXPECT_TRUE(Contains(text, "s_out=[+0.0000, +0.6000, +0.8000]")) << text;
  EXPECT_TRUE(Contains(text, "lockstep")) << text;
  EXPECT_FALSE(Contains(text, "power_w")) << text;
  m.optical_power_known(true);
  m.optical_power_w(1.25e-3);
  EXPECT_TRUE(Contains(ToText(m), "power_w=0.00125")) << ToText(m);
}

TEST(WaveplateCommandMessage, JsonHasEveryFieldAndTextShowsARate) {
  msg::WaveplateCommand m;
  m.bench_id("b1");
  m.controller_id("ctl-a");
  m.priority(5);
  m.sequence_number(11);
  m.answers_sample(10);
  m.sample_time_ns(2'000'000);
  m.phi({0.1, kNaN, -0.3});
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("WaveplateCommand"));
  EXPECT_EQ(json["controller_id"], "ctl-a");
  EXPECT_EQ(json["priority"], 5);
  EXPECT_TRUE(json["phi"][1].is_null());
  EXPECT_NEAR(json["phi"][2].get<double>(), -0.3, kTolerance);
  EXPECT_TRUE(json["phi_rate_per_s"].empty());
  std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "command from ctl-a (priority 5) #11 answers sample #10 t=0.002000 s")) << text;
  EXPECT_FALSE(Contains(text, "phi_rate_per_s")) << text;
  m.phi({0.1, 0.2, -0.3});
  m.phi_rate_per_s({1.5, 0.0, -2.0});
  text = ToText(m);
  EXPECT_TRUE(Contains(text, "phi=[+0.1000, +0.2000, -0.3000]")) << text;
  EXPECT_TRUE(Contains(text, "phi_rate_per_s=[+1.5000, +0.0000, -2.0000]")) << text;
}

TEST(WaveplateStateMessage, JsonHasEveryFieldAndTextSaysHoldingAndWhy) {
  msg::WaveplateState m;
  m.bench_id("b1");
  m.sequence_number(3);
  m.phi_applied({0.1, 0.2, 0.3});
  m.saturated({false, true, true});
  m.mode(msg::DRIVER_HOLDING);
  m.reason("no controller");
  m.commands_rejected(4);
  m.last_rejection("stale sample");
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("WaveplateState"));
  EXPECT_EQ(json["mode"], "DRIVER_HOLDING");
  EXPECT_EQ(json["saturated"], Json::parse("[false, true, true]"));
  EXPECT_EQ(json["reason"], "no controller");
  EXPECT_EQ(json["last_rejection"], "stale sample");
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "[b1] state #3 HOLDING obeyed=-")) << text;
  EXPECT_TRUE(Contains(text, "reason=\"no controller\"")) << text;
  EXPECT_TRUE(Contains(text, "saturated=[1,2]")) << text;
  EXPECT_TRUE(Contains(text, "rejected=4")) << text;
  EXPECT_FALSE(Contains(text, "ramp=")) << text;
  EXPECT_FALSE(Contains(text, "stand_ins")) << text;
  m.stand_ins(2);
  m.applied_controller_id("standby");
  EXPECT_EQ(ToJson(m)["applied_controller_id"], "standby");
  EXPECT_TRUE(Contains(ToText(m), "stand_ins=2 (last from standby)")) << ToText(m);
}

TEST(WaveplateStateMessage, TextOfAnActiveRampNamesTheControllerAndTheRamp) {
  msg::WaveplateState m;
  m.mode(msg::DRIVER_ACTIVE);
  m.obeyed_controller_id("ctl-a");
  m.obeyed_priority(5);
  m.phi_applied({0.1});
  m.phi_rate_per_s({2.0});
  m.ramp_start_time_ns(1'000'000);
  m.ramp_end_time_ns(3'000'000);
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "ACTIVE obeyed=ctl-a (priority 5)")) << text;
  EXPECT_TRUE(Contains(text, "phi_rate_per_s=[+2.0000] ramp=[0.001000, 0.003000] s")) << text;
  EXPECT_FALSE(Contains(text, "HOLDING")) << text;
  EXPECT_FALSE(Contains(text, "reason=")) << text;
  EXPECT_EQ(ToJson(m)["ramp_end_time_ns"], 3'000'000);
}

TEST(ControllerStatusMessage, JsonHasEveryFieldAndTextTheHealth) {
  msg::ControllerStatus m;
  m.bench_id("b1");
  m.controller_id("ctl-a");
  m.priority(5);
  m.law("gp");
  m.obeyed(true);
  m.condition("tracking");
  m.error_deg(1.23456);
  m.sigma_max(kNaN);
  m.compute_time_mean_s(2.5e-6);
  m.updates(100);
  m.missed_deadlines(2);
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("ControllerStatus"));
  EXPECT_EQ(json["law"], "gp");
  EXPECT_NEAR(json["error_deg"].get<double>(), 1.23456, kTolerance);
  EXPECT_TRUE(json["sigma_max"].is_null());
  EXPECT_EQ(json["updates"], 100u);
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "controller ctl-a (priority 5, gp) obeyed \"tracking\" error_deg=1.2346")) << text;
  EXPECT_TRUE(Contains(text, "compute_us mean=2.50")) << text;
  EXPECT_TRUE(Contains(text, "missed_deadlines=2")) << text;
  m.obeyed(false);
  EXPECT_TRUE(Contains(ToText(m), "standby")) << ToText(m);
}

TEST(DeviceDescriptionMessage, JsonNestsEveryStageFieldAndTextListsTheStages) {
  msg::Stage fixed;
  fixed.kind(msg::STAGE_FIXED_AXIS);
  fixed.name("wp1");
  fixed.axis({1.0, 0.0, 0.0});
  fixed.control_map().kind(msg::MAP_TABLE);
  fixed.control_map().table_control({-1.0, 1.0});
  fixed.control_map().table_angle_rad({-M_PI, kNaN});
  fixed.range().limited(true);
  fixed.range().max_phi(2.0);
  msg::Stage adjustable;
  adjustable.kind(msg::STAGE_ADJUSTABLE_AXIS);
  adjustable.retardance().controlled(true);
  msg::DeviceDescription m;
  m.bench_id("b1");
  m.driver_id("drv");
  m.stages({fixed, adjustable});
  m.max_slew_per_s(50.0);
  m.max_ramp_s(0.01);
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("DeviceDescription"));
  ASSERT_EQ(json["stages"].size(), 2u);
  const Json& stage = json["stages"][0];
  EXPECT_EQ(Keys(stage), IdlFields("Stage"));
  EXPECT_EQ(Keys(stage["control_map"]), IdlFields("ControlMap"));
  EXPECT_EQ(Keys(stage["range"]), IdlFields("ControlRange"));
  EXPECT_EQ(Keys(stage["retardance"]), IdlFields("StageAngle"));
  EXPECT_EQ(stage["kind"], "STAGE_FIXED_AXIS");
  EXPECT_EQ(stage["control_map"]["kind"], "MAP_TABLE");
  EXPECT_TRUE(stage["control_map"]["table_angle_rad"][1].is_null());
  EXPECT_EQ(stage["range"]["limited"], true);
  EXPECT_EQ(json["stages"][1]["kind"], "STAGE_ADJUSTABLE_AXIS");
  EXPECT_EQ(json["stages"][1]["retardance"]["controlled"], true);
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "[b1] device of driver drv: 2 stages")) << text;
  EXPECT_TRUE(Contains(text, "wp1 axis [+1.000, +0.000, +0.000], adjustable adjustable-axis")) << text;
  EXPECT_TRUE(Contains(text, "max_slew_per_s=50 max_ramp_s=0.01")) << text;
}

TEST(TargetMessage, JsonHasEveryFieldAndTextTheShapeAndItsOrigin) {
  msg::Target m;
  m.bench_id("b1");
  m.revision(2);
  m.kind(msg::TARGET_POINT);
  m.point({0.0, 0.6, 0.8});
  m.offset(kNaN);
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("Target"));
  EXPECT_EQ(json["kind"], "TARGET_POINT");
  EXPECT_TRUE(json["offset"].is_null());
  EXPECT_TRUE(Contains(ToText(m), "target revision 2: point [+0.0000, +0.6000, +0.8000] (request none: the scenario)"))
      << ToText(m);
  m.kind(msg::TARGET_SET);
  m.normal({0.0, 0.0, 1.0});
  m.offset(0.5);
  m.request_id("req-9");
  EXPECT_TRUE(Contains(ToText(m), "set [+0.0000, +0.0000, +1.0000]·S = 0.5000 (request req-9)")) << ToText(m);
}

TEST(TargetRequestMessage, JsonHasEveryFieldAndTextTheRequestedShape) {
  msg::TargetRequest m;
  m.bench_id("b1");
  m.request_id("req-9");
  m.kind(msg::TARGET_SET);
  m.normal({0.0, 0.0, 1.0});
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("TargetRequest"));
  EXPECT_EQ(json["kind"], "TARGET_SET");
  EXPECT_EQ(json["request_id"], "req-9");
  EXPECT_TRUE(Contains(ToText(m), "[b1] target request req-9: set [+0.0000, +0.0000, +1.0000]·S = 0.0000"))
      << ToText(m);
}

TEST(TargetReplyMessage, JsonHasEveryFieldAndTextSaysAcceptedOrRefused) {
  msg::TargetReply m;
  m.bench_id("b1");
  m.request_id("req-9");
  m.accepted(false);
  m.message("point is not a unit Stokes vector");
  m.revision(2);
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("TargetReply"));
  EXPECT_EQ(json["accepted"], false);
  EXPECT_EQ(json["message"], "point is not a unit Stokes vector");
  EXPECT_TRUE(Contains(ToText(m), "target reply to req-9: refused revision 2 \"point is not a unit Stokes vector\""))
      << ToText(m);
  m.accepted(true);
  m.revision(3);
  EXPECT_TRUE(Contains(ToText(m), "accepted revision 3")) << ToText(m);
}

}  // namespace
}  // namespace dpc::tools

namespace dpc::tools {
namespace {

TEST(BenchSummaryMessage, JsonHasEveryFieldAndTextSaysTheErrorAndTheDriver) {
  msg::BenchSummary m;
  m.bench_id("b1");
  m.sequence_number(9);
  m.samples(500);
  m.period_s(0.05);
  m.trail({1, 0, 0, 0, 0.6, 0.8});
  m.error_known(true);
  m.error_mean_deg(1.5);
  m.error_max_deg(3.25);
  m.state_known(true);
  m.mode(msg::DRIVER_ACTIVE);
  m.phi_applied({0.1, -0.2});
  m.saturated({false, true});
  const Json json = ToJson(m);
  EXPECT_EQ(Keys(json), IdlFields("BenchSummary"));
  EXPECT_EQ(json["saturated"], Json::parse("[false, true]"));
  const std::string text = ToText(m);
  EXPECT_TRUE(Contains(text, "[b1] summary #9 500 samples in 0.050 s error_deg=1.500 (max 3.250)")) << text;
  EXPECT_TRUE(Contains(text, "trail=1 DRIVER_ACTIVE")) << text;
}

}  // namespace
}  // namespace dpc::tools
