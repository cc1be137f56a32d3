#include "device_record.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace dpc::services {
namespace {

class DeviceRecordTest : public ::testing::Test {
 protected:
  std::string path_ = ::testing::TempDir() + "dpc_device_record_" + std::to_string(getpid());
  void TearDown() override { std::filesystem::remove(path_); }
};

TEST_F(DeviceRecordTest, ANewRecordHoldsNothingAndAWrittenOneGivesWhereTheMotionEnds) {
  {
    DeviceRecord record(path_, 3);
    EXPECT_FALSE(record.LastPhi().has_value());
    WaveplateMotion motion = WaveplateMotion::Still(ControlVector::Constant(3, 0.25));
    motion.rate_per_s = ControlVector::Constant(3, 10.0);
    motion.start_ns = 1'000'000;
    motion.end_ns = 3'000'000;  // 2 ms at 10 per second: +0.02
    motion.moving = true;
    record.Write(motion);
  }
  // Another process (a restarted driver) opens it.
  const DeviceRecord again(path_, 3);
  const auto phi = again.LastPhi();
  ASSERT_TRUE(phi.has_value());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR((*phi)[i], 0.27, 1e-12);
}

TEST_F(DeviceRecordTest, ARecordOfAnotherShapeIsIgnored) {
  {
    DeviceRecord record(path_, 3);
    record.Write(WaveplateMotion::Still(ControlVector::Constant(3, 0.5)));
  }
  EXPECT_FALSE(DeviceRecord(path_, 4).LastPhi().has_value());
}

TEST_F(DeviceRecordTest, ARecordTornByAKillInTheMiddleOfAWriteOrHoldingGarbageIsIgnored) {
  {
    DeviceRecord record(path_, 2);
    record.Write(WaveplateMotion::Still(ControlVector::Constant(2, 0.5)));
  }
  // The sequence number (bytes 12–15) odd: a write under way when the writer died.
  {
    std::fstream file(path_, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(12);
    const uint32_t odd = 3;
    file.write(reinterpret_cast<const char*>(&odd), sizeof odd);
  }
  EXPECT_FALSE(DeviceRecord(path_, 2).LastPhi().has_value());
  // A NaN in φ (bytes 16–23), the sequence even again.
  {
    std::fstream file(path_, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(12);
    const uint32_t even = 4;
    file.write(reinterpret_cast<const char*>(&even), sizeof even);
    const double nan = std::nan("");
    file.write(reinterpret_cast<const char*>(&nan), sizeof nan);
  }
  EXPECT_FALSE(DeviceRecord(path_, 2).LastPhi().has_value());
}

TEST_F(DeviceRecordTest, APathThatIsNotARegularFileIsRefusedNamingIt) {
  ASSERT_EQ(::mkfifo(path_.c_str(), 0600), 0);
  try {
    DeviceRecord record(path_, 3);
    FAIL() << "a FIFO accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path_), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dpc::services
