// What fuzzing (tests/fuzz) found, kept as tests of the ordinary build: payloads and messages a
// peer can send that once aborted a service or passed a check they should not have.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "dpc/bus/message_conversion.h"
#include "dpc/bus/topics.h"
#include "dpc/config/scenario_builders.h"

namespace dpc::bus {
namespace {

/// A valid sample as the wire carries it (CDR, little-endian encapsulation).
eprosima::fastrtps::rtps::SerializedPayload_t Serialized(msg::StokesSample sample) {
  TopicTraits<msg::StokesSample>::PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return payload;
}

msg::StokesSample Sample() {
  msg::StokesSample s;
  s.bench_id("bench1");
  s.sequence_number(7);
  s.s_in({1.0, 0.0, 0.0});
  s.s_out({0.0, 0.6, 0.8});
  return s;
}

TEST(HostilePayload, AnUnknownEncapsulationOrABooleanThatIsNeitherZeroNorOneIsDroppedNotThrown) {
  TopicTraits<msg::StokesSample>::PubSubType type;
  msg::StokesSample out;
  {
    auto payload = Serialized(Sample());
    ASSERT_TRUE(type.deserialize(&payload, &out));
    EXPECT_EQ(out.sequence_number(), 7u);
  }
  {
    auto payload = Serialized(Sample());
    payload.data[0] = 1;  // the encapsulation's first byte: Fast CDR throws BadParamException
    bool result = true;
    EXPECT_NO_THROW(result = type.deserialize(&payload, &out));
    EXPECT_FALSE(result);
  }
  {
    auto payload = Serialized(Sample());
    payload.data[payload.length - 1] = 2;  // the last field, `lockstep`, a boolean
    bool result = true;
    EXPECT_NO_THROW(result = type.deserialize(&payload, &out));
    EXPECT_FALSE(result);
  }
  {
    auto payload = Serialized(Sample());
    payload.length = 9;  // truncated
    bool result = true;
    EXPECT_NO_THROW(result = type.deserialize(&payload, &out));
    EXPECT_FALSE(result);
  }
}

TEST(HostilePayload, AStateWhoseMotionLeavesTheFiniteNumbersIsRefused) {
  msg::WaveplateState s;
  s.phi_applied({1e308, 0.0, 0.0});
  s.phi_rate_per_s({1e308, 0.0, 0.0});
  s.ramp_start_time_ns(0);
  s.ramp_end_time_ns(1'000'000'000);
  DriverState read;
  EXPECT_NE(ReadState(s, 3, &read).find("does not stay finite"), std::string::npos) << ReadState(s, 3, &read);
  s.phi_applied(std::vector<double>(20, 0.0));
  s.phi_rate_per_s({});
  EXPECT_NE(ReadState(s, 20, &read).find("oversized"), std::string::npos) << ReadState(s, 20, &read);
}

TEST(HostilePayload, ADeviceBeyondTheWiresBoundsIsRefused) {
  DeviceDescription read;
  // 17 controls (15 fixed-axis stages and an adjustable one with both angles controlled): a
  // command carries at most 16 (MAX_CONTROLS).
  std::vector<StageConfig> stages = StagesFromAxes("131313131313131");
  StageConfig adjustable;
  adjustable.kind = StageConfig::Kind::kAdjustableAxis;
  adjustable.retardance.controlled = true;
  adjustable.orientation.controlled = true;
  stages.push_back(adjustable);
  EXPECT_NE(ReadDevice(DeviceMessage(DeviceDescription{"d", stages, 0.0, 0.0}, "b"), &read).find("oversized"),
            std::string::npos);
  // A table of 65 points (MAX_MAP_POINTS = 64).
  msg::DeviceDescription d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.stages()[0].control_map().kind(msg::MAP_TABLE);
  std::vector<double> controls(65), angles(65);
  for (int i = 0; i < 65; ++i) controls[i] = angles[i] = i;
  d.stages()[0].control_map().table_control(controls);
  d.stages()[0].control_map().table_angle_rad(angles);
  EXPECT_NE(ReadDevice(d, &read).find("oversized"), std::string::npos) << ReadDevice(d, &read);
  // A linear map carrying coefficients it does not use: accepted, and none kept.
  d = DeviceMessage(DeviceDescription{"d", StagesFromAxes("131"), 0.0, 0.0}, "b");
  d.stages()[0].control_map().coefficients_rad(std::vector<double>(10, 1.0));
  ASSERT_EQ(ReadDevice(d, &read), "");
  EXPECT_TRUE(read.stages[0].map.coefficients_rad.empty());
}

}  // namespace
}  // namespace dpc::bus
