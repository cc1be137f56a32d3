// Tests of the real instruments' checks (instrument_validation.cc): each test starts from a
// valid scenario with a TCP waveplate device and a serial polarimeter, breaks one field and
// checks where ValidateScenario locates the error.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "dpc/config/scenario_validation.h"
#include "support/scenario_fixture.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using testing::kNaN;

class InstrumentValidationTest : public testing::ScenarioFixture {
 protected:
  void SetUp() override {
    for (StageConfig& stage : scenario_.stages) stage.range = ControlRange{-5.0, 5.0};
    WaveplateDeviceConfig device;
    device.link.port = 5025;
    scenario_.waveplate_device = device;
    PolarimeterDeviceConfig polarimeter;
    polarimeter.link.kind = InstrumentLinkConfig::Kind::kSerial;
    polarimeter.link.path = "/dev/ttyUSB1";
    scenario_.polarimeter_device = polarimeter;
  }
  WaveplateDeviceConfig& device() { return *scenario_.waveplate_device; }
  PolarimeterDeviceConfig& polarimeter() { return *scenario_.polarimeter_device; }
};

TEST_F(InstrumentValidationTest, TheDefaultsWithALinkAndRangesAreValid) {
  EXPECT_EQ(ErrorLocation(), "(valid)") << ErrorMessage();
}

TEST_F(InstrumentValidationTest, ATcpLinkIsAnIpv4AddressAndAPort) {
  device().link.host = "bench-epc.local";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.tcp.host");
  EXPECT_THAT(ErrorMessage(), HasSubstr("no names"));
  device().link.host = "127.0.0.1";
  device().link.port = 0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.tcp.port");
  device().link.port = 70000;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.tcp.port");
}

TEST_F(InstrumentValidationTest, ASerialLinkIsAnAbsolutePathAtAStandardBaudRate) {
  polarimeter().link.path = "ttyUSB1";
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.link.serial.path");
  polarimeter().link.path = "/dev/ttyUSB1";
  polarimeter().link.baud = 12345;
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.link.serial.baud");
}

TEST_F(InstrumentValidationTest, TimeoutsAndReconnectionDelaysAreInRange) {
  device().link.response_timeout_s = 0.0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.response_timeout_s");
  device().link.response_timeout_s = kNaN;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.response_timeout_s");
  device().link.response_timeout_s = 11.0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.response_timeout_s");
  device().link.response_timeout_s = 0.05;
  device().link.reconnect_min_s = 3.0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.link.reconnect_max_s");
}

TEST_F(InstrumentValidationTest, TheSetCommandFormatsIntoOneLineThatSaysWhatToSet) {
  device().set_command = ":SOUR{channel}:VOLT {volts:.4q}";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.set_command");
  EXPECT_THAT(ErrorMessage(), HasSubstr("cannot be formatted"));
  device().set_command = ":SOUR{channel}:VOLT {voltage}";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.set_command");
  device().set_command = ":SOUR{channel}:OUTP ON";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.set_command");
  EXPECT_THAT(ErrorMessage(), HasSubstr("neither {volts} nor {code}"));
  device().set_command = "CH{channel} {code}\nRST";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.set_command");
  EXPECT_THAT(ErrorMessage(), HasSubstr("control character"));
  device().set_command = "DAC{channel}={code:08x}";
  EXPECT_EQ(ErrorLocation(), "(valid)") << ErrorMessage();
  EXPECT_EQ(FormatSetCommand(device().set_command, 3, 1.5, 255), "DAC3=000000ff");
  EXPECT_EQ(FormatSetCommand(":SOUR{channel}:VOLT {volts:.4f}", 2, -1.23456, 0), ":SOUR2:VOLT -1.2346");
}

TEST_F(InstrumentValidationTest, OneDistinctChannelPerControl) {
  device().channels = {1, 2};
  EXPECT_EQ(ErrorLocation(), "waveplate_device.channels");
  device().channels = {1, 2, 2};
  EXPECT_EQ(ErrorLocation(), "waveplate_device.channels[2]");
  device().channels = {1, 0, 3};
  EXPECT_EQ(ErrorLocation(), "waveplate_device.channels[1]");
  device().channels = {8, 1, 5};
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(InstrumentValidationTest, EveryControlHasARangeInsideTheFullScale) {
  scenario_.stages[1].range.reset();
  EXPECT_EQ(ErrorLocation(), "stages[1].range");
  EXPECT_THAT(ErrorMessage(), HasSubstr("needs a range"));
  scenario_.stages[1].range = ControlRange{-12.0, 5.0};
  EXPECT_EQ(ErrorLocation(), "stages[1].range");
  EXPECT_THAT(ErrorMessage(), HasSubstr("outside the device's full scale [-10, 10] V"));
  scenario_.stages[1].range = ControlRange{-5.0, 5.0};
  device().volts_min = 1.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].range");
  device().volts_min = 20.0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.volts_max");
  device().volts_min = -10.0;
  device().dac_bits = 33;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.dac_bits");
  device().dac_bits = 0;
  device().max_slew_v_per_s = -1.0;
  EXPECT_EQ(ErrorLocation(), "waveplate_device.max_slew_v_per_s");
}

TEST_F(InstrumentValidationTest, TheReadCommandNamesItsChannel) {
  device().read_command = ":VOLT?";
  EXPECT_EQ(ErrorLocation(), "waveplate_device.read_command");
  device().read_command = "";
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(InstrumentValidationTest, APolarimeterHasAQueryAndAMinimumDegreeOfPolarization) {
  polarimeter().query = "";
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.query");
  polarimeter().query = std::string(300, 'Q');
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.query");
  polarimeter().query = ":MEAS:SOP?";
  polarimeter().min_dop = 0.0;
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.min_dop");
  polarimeter().min_dop = 1.5;
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.min_dop");
}

TEST_F(InstrumentValidationTest, AStreamsStartIsOneLineAndOnlyForAStream) {
  polarimeter().stream_start = ":MEAS:STREAM SOP 1000";
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.stream_start");  // without stream: true
  polarimeter().stream = true;
  EXPECT_EQ(ErrorLocation(), "(valid)");
  polarimeter().stream_start = "ON\nOFF";
  EXPECT_EQ(ErrorLocation(), "polarimeter_device.stream_start");
  polarimeter().stream_start = "";
  EXPECT_EQ(ErrorLocation(), "(valid)");  // an instrument that streams by itself
}

}  // namespace
}  // namespace dpc
