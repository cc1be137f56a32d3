#include "dpc/scenario_io/scenario_writer.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "support/scenario_texts.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using namespace dpc::testing;

TEST(ScenarioWriterTest, PaperScenarioRoundTrips) {
  const ScenarioConfig paper = PaperScenario("3131");
  ExpectSameScenario(ScenarioFromProto(ScenarioToProto(paper)), paper);
  ExpectSameScenario(FromText(ScenarioToText(paper)), paper);
}

TEST(ScenarioWriterTest, EveryFieldRoundTrips) {
  for (const char* text : {kFixedAxisText, kAdjustableAxisText, kConditionTablesText}) {
    const ScenarioConfig config = FromText(text);
    SCOPED_TRACE(config.name);
    ExpectSameScenario(ScenarioFromProto(ScenarioToProto(config)), config);
    ExpectSameScenario(FromText(ScenarioToText(config)), config);
  }
}

TEST(ScenarioWriterTest, InstrumentsRoundTrip) {
  const ScenarioConfig config = FromText(kInstrumentsText);
  ASSERT_TRUE(config.waveplate_device.has_value());
  EXPECT_EQ(config.waveplate_device->link.kind, InstrumentLinkConfig::Kind::kSerial);
  EXPECT_EQ(config.waveplate_device->link.baud, 57600);
  EXPECT_EQ(config.waveplate_device->channels, (std::vector<int>{4, 2, 7}));
  ASSERT_TRUE(config.polarimeter_device.has_value());
  EXPECT_EQ(config.polarimeter_device->reply, PolarimeterDeviceConfig::Reply::kInputAndOutput);
  EXPECT_EQ(config.polarimeter_device->link.port, 5025);
  EXPECT_EQ(config.polarimeter_device->link.reconnect_max_s, 2.0);  // the default
  EXPECT_TRUE(config.polarimeter_device->stream);
  EXPECT_EQ(config.polarimeter_device->stream_start, "READ:STREAM ON");
  ExpectSameScenario(FromText(ScenarioToText(config)), config);
  // Without them, none appear.
  EXPECT_EQ(ScenarioToText(PaperScenario("131")).find("device"), std::string::npos);
}

TEST(ScenarioWriterTest, DoublesRoundTripExactly) {
  ScenarioConfig config = PaperScenario("131");
  config.controller.step = 0.1 + 0.2;
  config.stages[0].map.rad_per_unit = 1.0 / 3.0;
  config.stages[1].axis = Vector3(std::sqrt(2.0), -1e-300, 1e300);
  config.simulation.statistics_start_s = std::nextafter(5e-3, 1.0);
  ExpectSameScenario(FromText(ScenarioToText(config)), config);
}

TEST(ScenarioWriterTest, TextNamesElementalAxesByEnum) {
  const std::string text = ScenarioToText(PaperScenario("131"));
  EXPECT_THAT(text, HasSubstr("axis: S1"));
  EXPECT_THAT(text, HasSubstr("axis: S3"));
  EXPECT_THAT(text, HasSubstr("method: GP"));
}

}  // namespace
}  // namespace dpc
