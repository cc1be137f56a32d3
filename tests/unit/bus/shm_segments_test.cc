// The stale shared-memory files of Fast DDS: what a dead process left is removed, what a live
// one holds (an flock on its "_el" file) or is still creating is not, and nothing else is
// touched. Files are made in a temporary directory, as Fast DDS names them in /dev/shm.

#include "dpc/bus/shm_segments.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace dpc::bus {
namespace {

namespace fs = std::filesystem;

class ShmSegmentsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dpc-shm-test-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (held_fd_ >= 0) ::close(held_fd_);
    fs::remove_all(dir_);
  }
  /// A file of `name`, last modified `age_s` ago.
  void Make(const std::string& name, double age_s = 60.0) {
    std::ofstream(dir_ / name) << "x";
    const auto when = fs::file_time_type::clock::now() - std::chrono::seconds(static_cast<int>(age_s));
    fs::last_write_time(dir_ / name, when);
  }
  void Port(int port, double age_s = 60.0) {
    const std::string base = "fastrtps_port" + std::to_string(port);
    Make(base, age_s);
    Make(base + "_el", age_s);
    Make("sem." + base + "_mutex", age_s);
  }
  void Segment(const std::string& id, double age_s = 60.0) {
    Make("fastrtps_" + id, age_s);
    Make("fastrtps_" + id + "_el", age_s);
  }
  /// Holds the lock of `name` as its live owner does.
  void Hold(const std::string& name) {
    held_fd_ = ::open((dir_ / name).c_str(), O_RDONLY);
    ASSERT_GE(held_fd_, 0);
    ASSERT_EQ(::flock(held_fd_, LOCK_EX | LOCK_NB), 0);
  }
  bool Exists(const std::string& name) { return fs::exists(dir_ / name); }

  fs::path dir_;
  int held_fd_ = -1;
};

TEST_F(ShmSegmentsTest, WhatADeadProcessLeftIsRemovedWhatALiveOneHoldsIsNot) {
  Port(7411);                          // dead
  Segment("cd21acaaf3a30d68");         // dead
  Port(7413);                          // alive
  Segment("0123456789abcdef");         // alive
  Hold("fastrtps_port7413_el");
  const int first = held_fd_;
  held_fd_ = -1;
  Hold("fastrtps_0123456789abcdef_el");
  const StaleShmCleanup result = RemoveStaleShmFiles(dir_.string());
  ::close(first);
  EXPECT_EQ(result.ports_removed, 1);
  EXPECT_EQ(result.segments_removed, 1);
  EXPECT_EQ(result.in_use, 2);
  EXPECT_TRUE(result.errors.empty());
  const std::vector<std::string> lines = DescribeShmCleanup(result);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("1 Fast DDS port, 1 segment (2 in use)"), std::string::npos) << lines[0];
  EXPECT_TRUE(DescribeShmCleanup(StaleShmCleanup{}).empty());
  for (const char* gone : {"fastrtps_port7411", "fastrtps_port7411_el", "sem.fastrtps_port7411_mutex",
                           "fastrtps_cd21acaaf3a30d68", "fastrtps_cd21acaaf3a30d68_el"}) {
    EXPECT_FALSE(Exists(gone)) << gone;
  }
  for (const char* kept : {"fastrtps_port7413", "fastrtps_port7413_el", "sem.fastrtps_port7413_mutex",
                           "fastrtps_0123456789abcdef", "fastrtps_0123456789abcdef_el"}) {
    EXPECT_TRUE(Exists(kept)) << kept;
  }
}

TEST_F(ShmSegmentsTest, FilesBeingCreatedAndOtherFilesAreLeftAlone) {
  Port(7415, /*age_s=*/0.0);  // a participant starting: its lock is not taken yet
  Make("dpc-waveplates-0-bench1-driver");
  Make("fastrtps_port7411_el.bak");
  Make("fastrtps_short_el");
  Make("xfastrtps_port7411_el");
  const StaleShmCleanup result = RemoveStaleShmFiles(dir_.string());
  EXPECT_EQ(result.ports_removed + result.segments_removed + result.in_use, 0);
  EXPECT_TRUE(Exists("fastrtps_port7415_el"));
  EXPECT_TRUE(Exists("dpc-waveplates-0-bench1-driver"));
  EXPECT_TRUE(Exists("fastrtps_port7411_el.bak"));
  EXPECT_TRUE(Exists("fastrtps_short_el"));
  EXPECT_TRUE(Exists("xfastrtps_port7411_el"));
  // Once old enough, the same files are stale.
  EXPECT_EQ(RemoveStaleShmFiles(dir_.string(), 0.0).ports_removed, 1);
  EXPECT_FALSE(Exists("fastrtps_port7415"));
}

TEST_F(ShmSegmentsTest, AMissingDirectoryIsNothingToClean) {
  const StaleShmCleanup result = RemoveStaleShmFiles((dir_ / "none").string());
  EXPECT_EQ(result.ports_removed + result.segments_removed + result.in_use, 0);
  EXPECT_TRUE(result.errors.empty());
}

TEST_F(ShmSegmentsTest, AProfileUsesSharedMemoryWhenATransportIsOfTypeShm) {
  EXPECT_FALSE(ProfilesUseSharedMemory(std::string(DPC_SOURCE_DIR) + "/deploy/fastdds/loopback.xml"));
  std::ofstream(dir_ / "shm.xml") << "<transport_descriptor><transport_id>s</transport_id>\n  <type> SHM </type>";
  EXPECT_TRUE(ProfilesUseSharedMemory((dir_ / "shm.xml").string()));
  EXPECT_FALSE(ProfilesUseSharedMemory((dir_ / "missing.xml").string()));
}

}  // namespace
}  // namespace dpc::bus
