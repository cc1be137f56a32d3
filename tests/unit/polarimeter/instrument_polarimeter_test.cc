// A real polarimeter over a line protocol, against a scripted instrument on 127.0.0.1: readings,
// refused replies, timeouts, reconnection; and the bench's loop driven by it.

#include "instrument_polarimeter.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <thread>

#include "dpc/bench/clock.h"
#include "support/line_server.h"

namespace dpc::services {
namespace {

using namespace std::chrono_literals;

PolarimeterDeviceConfig Device(int port, PolarimeterDeviceConfig::Reply reply = PolarimeterDeviceConfig::Reply::kOutput) {
  PolarimeterDeviceConfig d;
  d.link.port = port;
  d.link.response_timeout_s = 0.3;  // generous: a loaded test machine must not look like a fault
  d.link.reconnect_min_s = 0.05;
  d.link.reconnect_max_s = 0.2;
  d.reply = reply;
  return d;
}

TEST(InstrumentPolarimeterTest, ReadsTheStokesVectorsItIsAskedFor) {
  dpc::testing::LineServer server([](const std::string& line) -> std::optional<std::string> {
    if (line == ":MEAS:SOP?") return "0.000000,0.600000,0.800000\n";
    return "ERR\n";
  });
  InstrumentPolarimeter polarimeter(Device(server.port()));
  std::string why;
  const int64_t before = MonotonicNs();
  const auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  EXPECT_FALSE(reading->s_in.has_value());
  ASSERT_TRUE(reading->s_out.has_value());
  EXPECT_TRUE(reading->s_out->isApprox(StokesVector(0, 0.6, 0.8)));
  EXPECT_GE(reading->reply_ns, before);
  EXPECT_EQ(polarimeter.counters().readings, 1u);
  EXPECT_EQ(polarimeter.counters().connects, 1u);
}

TEST(InstrumentPolarimeterTest, BothVectorsInOneReply) {
  dpc::testing::LineServer server([](const std::string&) -> std::optional<std::string> {
    return "1,0,0, 0,0,-0.5\n";  // the output partly polarized: normalized
  });
  InstrumentPolarimeter polarimeter(Device(server.port(), PolarimeterDeviceConfig::Reply::kInputAndOutput));
  std::string why;
  const auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  EXPECT_TRUE(reading->s_in->isApprox(StokesVector::UnitX()));
  EXPECT_TRUE(reading->s_out->isApprox(-StokesVector::UnitZ()));
}

TEST(InstrumentPolarimeterTest, TheOpticalPowerAtTheEndOfAReplyIsReadToo) {
  std::atomic<int> calls{0};
  dpc::testing::LineServer server([&](const std::string&) -> std::optional<std::string> {
    return ++calls == 1 ? "0,0.6,0.8,1.25e-3\n" : "0,0.6,0.8,-1\n";
  });
  PolarimeterDeviceConfig device = Device(server.port());
  device.reports_power = true;
  InstrumentPolarimeter polarimeter(device);
  std::string why;
  const auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  ASSERT_TRUE(reading->power_w.has_value());
  EXPECT_DOUBLE_EQ(*reading->power_w, 1.25e-3);
  EXPECT_TRUE(reading->s_out->isApprox(StokesVector(0, 0.6, 0.8)));
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());  // a negative power
  EXPECT_NE(why.find("power"), std::string::npos) << why;
}

TEST(InstrumentPolarimeterTest, AStreamIsStartedAtConnectionAndReadNewestLineFirst) {
  std::atomic<int> starts{0}, queries{0};
  dpc::testing::LineServer server([&](const std::string& line) -> std::optional<std::string> {
    if (line == ":MEAS:STREAM SOP 100") {
      ++starts;
      return "1,0,0\n0,1,0\n0,0,1\n";  // three lines at once: the reader was slower
    }
    ++queries;
    return std::nullopt;
  });
  PolarimeterDeviceConfig device = Device(server.port());
  device.stream = true;
  device.stream_start = ":MEAS:STREAM SOP 100";
  device.link.response_timeout_s = 0.1;
  InstrumentPolarimeter polarimeter(device);
  std::string why;
  auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  EXPECT_TRUE(reading->s_out->isApprox(StokesVector::UnitZ()));  // the newest of the three
  EXPECT_EQ(polarimeter.counters().overtaken, 2u);
  EXPECT_EQ(polarimeter.counters().queries, 0u);
  // Nothing more comes: no reading, said as the stream's, and nothing was queried.
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_NE(why.find("the stream"), std::string::npos) << why;
  EXPECT_EQ(polarimeter.counters().timeouts, 1u);
  // The instrument hangs up: the stream is started again on the next connection.
  server.HangUp();
  for (int i = 0; i < 50 && starts < 2; ++i) {
    reading = polarimeter.Measure(MonotonicNs(), &why);
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_EQ(starts.load(), 2);
  EXPECT_EQ(queries.load(), 0);
  EXPECT_EQ(polarimeter.counters().connects, 2u);
}

TEST(InstrumentPolarimeterTest, GarbageAndSilenceGiveNoReadingAndSayWhy) {
  std::atomic<int> mode{0};
  dpc::testing::LineServer server([&](const std::string&) -> std::optional<std::string> {
    if (mode == 0) return "OVERRANGE\n";
    if (mode == 1) return std::nullopt;
    return "0,1,0\n";
  });
  InstrumentPolarimeter polarimeter(Device(server.port()));
  std::string why;
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_NE(why.find("not a number"), std::string::npos) << why;
  EXPECT_EQ(polarimeter.counters().refused_replies, 1u);
  mode = 1;
  const auto started = std::chrono::steady_clock::now();
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - started, 1500ms);  // the timeout, not more
  EXPECT_NE(why.find("no reply"), std::string::npos) << why;
  EXPECT_EQ(polarimeter.counters().timeouts, 1u);
  mode = 2;
  const auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  EXPECT_TRUE(reading->s_out->isApprox(StokesVector::UnitY()));
}

TEST(InstrumentPolarimeterTest, AHangUpIsReconnectedAfterTheBackoffWithoutWaitingForIt) {
  dpc::testing::LineServer server([](const std::string&) -> std::optional<std::string> { return "0,0,1\n"; });
  InstrumentPolarimeter polarimeter(Device(server.port()));
  std::string why;
  ASSERT_TRUE(polarimeter.Measure(MonotonicNs(), &why).has_value()) << why;
  server.HangUp();
  std::this_thread::sleep_for(30ms);
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  // Before the backoff is over it says so at once, without trying.
  const auto started = std::chrono::steady_clock::now();
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - started, 10ms);
  EXPECT_NE(why.find("next attempt"), std::string::npos) << why;
  std::this_thread::sleep_for(80ms);
  const auto reading = polarimeter.Measure(MonotonicNs(), &why);
  ASSERT_TRUE(reading.has_value()) << why;
  EXPECT_EQ(polarimeter.counters().connects, 2u);
  EXPECT_GE(server.connections(), 2);
}

TEST(InstrumentPolarimeterTest, NoInstrumentIsAFailedConnectionThatBacksOff) {
  int port = 0;
  {
    dpc::testing::LineServer gone([](const std::string&) -> std::optional<std::string> { return std::nullopt; });
    port = gone.port();
  }
  InstrumentPolarimeter polarimeter(Device(port));
  std::string why;
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_NE(why.find("cannot connect"), std::string::npos) << why;
  EXPECT_EQ(polarimeter.counters().failed_connects, 1u);
  EXPECT_FALSE(polarimeter.Measure(MonotonicNs(), &why).has_value());
  EXPECT_EQ(polarimeter.counters().failed_connects, 1u);  // not before the backoff
}

}  // namespace
}  // namespace dpc::services
