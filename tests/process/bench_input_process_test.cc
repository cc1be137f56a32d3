// What a running bench does with malformed input on the bus: counted, reported, never applied.
// Real processes on loopback, the test writing the bad messages through its own participant.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include "support/bench_fixture.h"
#include "support/json_lines.h"

namespace dpc {
namespace {

using dpc::testing::Eventually;
using dpc::testing::LastJsonLine;
using dpc::testing::Process;
using dpc::testing::SeenState;
using namespace std::chrono_literals;

class BenchInputTest : public dpc::testing::BenchFixture {};

TEST_F(BenchInputTest, MalformedCommandsAndSamplesAreCountedAndNeverApplied) {
  StartObserver(45);
  StartDriver();
  StartController("A", 0);
  StartPolarimeter({"--rate-hz", "1000"});
  ASSERT_TRUE(Eventually([&] { return AppliedBy("A") > 200; }, 20s)) << Logs();
  auto commands = participant_->MakeWriter<msg::WaveplateCommand>("bench1", "intruder");
  auto samples = participant_->MakeWriter<msg::StokesSample>("bench1");
  ASSERT_TRUE(Eventually([&] { return commands->matched_readers() > 0 && samples->matched_readers() > 0; }, 10s));
  auto bad_command = [](std::vector<double> phi) {
    msg::WaveplateCommand c;
    c.bench_id("bench1");
    c.controller_id("intruder");
    c.priority(100);  // would win if it were valid
    c.answers_sample(1);
    c.phi(std::move(phi));
    return c;
  };
  // One at a time, re-sent every 50 ms until counted: the periodic topics are best effort and
  // keep only the latest sample, so a write may be lost or replaced.
  auto write_until = [](const std::function<void()>& write, const std::function<bool()>& counted) {
    for (int attempt = 0; attempt < 100; ++attempt) {
      write();
      if (Eventually(counted, 50ms)) return true;
    }
    return false;
  };
  for (const auto& phi : {std::vector<double>{NAN, 0.0, 0.0}, std::vector<double>{0.1, 0.2},
                          std::vector<double>(17, 0.0), std::vector<double>{INFINITY, 0.0, 0.0}}) {
    const uint64_t rejected_before = LatestState()->commands_rejected();
    ASSERT_TRUE(write_until([&] { commands->Write(bad_command(phi)); },
                            [&] { return LatestState()->commands_rejected() > rejected_before; }))
        << phi.size() << " values: " << Logs();
  }
  EXPECT_TRUE(SoonObeys("A")) << LatestState()->reason().to_string();
  const auto state = LatestState();
  for (double v : state->phi_applied()) EXPECT_TRUE(std::isfinite(v));
  EXPECT_FALSE(state->last_rejection().to_string().empty());

  msg::StokesSample sample;
  sample.bench_id("bench1");
  sample.sequence_number(1);
  sample.s_in({1.0, 1.0, 0.0});   // not unit
  sample.s_out({1.0, 0.0, 0.0});
  ASSERT_TRUE(write_until([&] { samples->Write(sample); }, [&] {
    auto status = Status("A");
    return status && status->rejected_samples() >= 1;
  })) << Logs();
  sample.s_in({NAN, 0.0, 0.0});
  const uint64_t rejected_samples = Status("A")->rejected_samples();
  ASSERT_TRUE(write_until([&] { samples->Write(sample); }, [&] {
    auto status = Status("A");
    return status && status->rejected_samples() > rejected_samples;
  })) << Logs();
  EXPECT_NE(Status("A")->last_rejection().to_string().find("s_in"), std::string::npos);
  // The loop kept running on the good samples.
  const size_t applied = AppliedBy("A");
  EXPECT_TRUE(Eventually([&] { return AppliedBy("A") > applied + 100; }, 5s));
}

TEST_F(BenchInputTest, ACommandInTheNameOfAnotherControllerIsRefusedAndNeverApplied) {
  StartObserver(47);
  StartDriver();
  StartController("A", 0);
  StartPolarimeter({"--rate-hz", "1000"});
  ASSERT_TRUE(Eventually([&] { return AppliedBy("A") > 200; }, 20s)) << Logs();
  // A participant writing in its own partition ("intruder") commands under A's id, and a
  // priority that would win: the driver refuses it (the id is not its writer's).
  auto commands = participant_->MakeWriter<msg::WaveplateCommand>("bench1", "intruder");
  ASSERT_TRUE(Eventually([&] { return commands->matched_readers() > 0; }, 10s));
  const uint64_t rejected_before = LatestState()->commands_rejected();
  msg::WaveplateCommand spoof;
  spoof.bench_id("bench1");
  spoof.controller_id("A");
  spoof.priority(1000);
  spoof.phi({0.9, 0.9, 0.9});
  ASSERT_TRUE(Eventually(
      [&] {
        spoof.answers_sample(LatestState()->answers_sample());
        commands->Write(spoof);
        return LatestState()->commands_rejected() > rejected_before;
      },
      10s))
      << Logs();
  EXPECT_NE(LatestState()->last_rejection().to_string().find("is not its writer's"), std::string::npos)
      << LatestState()->last_rejection().to_string();
  for (const auto& s : States()) {
    for (double v : s.state.phi_applied()) EXPECT_NE(v, 0.9);
  }
  EXPECT_TRUE(SoonObeys("A"));
}

TEST_F(BenchInputTest, ASecondDriverOnTheBenchIsDetectedAndTheLaterOneLeaves) {
  StartObserver(38);
  StartDriver();
  StartController("A", 0);
  StartPolarimeter({"--rate-hz", "1000"});
  ASSERT_TRUE(Eventually([&] { return AppliedBy("A") > 200; }, 20s)) << Logs();
  // A second driver of bench1 (its own device record): it sees the first one's target and exits.
  Process& second = Start(DPC_DRIVER_BINARY, {"--device-record", dir_ + "/second.record"}, "second_driver");
  const auto code = second.Wait(15s);
  ASSERT_TRUE(code.has_value()) << "the second driver kept running: " << Logs();
  EXPECT_EQ(*code, 1);
  EXPECT_NE(second.Log().find("another driver drives bench bench1"), std::string::npos) << second.Log();
  // The first one saw it too, said so, and drives on.
  const size_t applied = AppliedBy("A");
  EXPECT_TRUE(Eventually([&] { return AppliedBy("A") > applied + 200; }, 10s));
  EXPECT_TRUE(SoonObeys("A"));
  EXPECT_NE(Logs().find("a second driver on bench bench1"), std::string::npos) << Logs();
}

/// A polarimeter whose --trace is a pipe that nobody reads: its loop blocks in write() for good,
/// as it would in a call into Fast DDS that never returns. The read end stays open (never
/// read) as long as the returned descriptor.
int OpenUnreadPipe(const std::string& path) {
  if (mkfifo(path.c_str(), 0600) != 0) return -1;
  return open(path.c_str(), O_RDWR | O_NONBLOCK);
}

TEST_F(BenchInputTest, AServiceStuckInACallThatNeverReturnsSaysWhereAndExitsWithCode1) {
  StartObserver(38);
  // Not stuck: a process stopped as a whole (SIGSTOP) for longer than the limit, then resumed.
  Process& paused = StartPolarimeter({"--rate-hz", "2000", "--stuck-exit-s", "1"}, "polarimeter_paused");
  ASSERT_TRUE(Eventually([&] { return paused.Log().find("real time at") != std::string::npos; }, 20s)) << paused.Log();
  paused.Signal(SIGSTOP);
  std::this_thread::sleep_for(4s);
  paused.Signal(SIGCONT);
  std::this_thread::sleep_for(3s);
  ASSERT_TRUE(paused.running()) << paused.Log();
  paused.Signal(SIGTERM);
  EXPECT_EQ(paused.Wait(20s), std::optional<int>(0)) << paused.Log();
  EXPECT_EQ(paused.Log().find("stuck"), std::string::npos) << paused.Log();

  const int pipe_fd = OpenUnreadPipe(dir_ + "/stuck_trace");
  ASSERT_GE(pipe_fd, 0) << std::strerror(errno);
  Process& stuck = StartPolarimeter({"--rate-hz", "2000", "--trace", dir_ + "/stuck_trace", "--stuck-exit-s", "2"});
  const auto code = stuck.Wait(30s);
  ASSERT_TRUE(code.has_value()) << "still running: " << stuck.Log();
  EXPECT_EQ(*code, 1) << stuck.Log();
  EXPECT_NE(stuck.Log().find("stuck: its loop has not turned for 2."), std::string::npos) << stuck.Log();
  EXPECT_NE(stuck.Log().find("(stuck in: its samples)"), std::string::npos) << stuck.Log();

  // The guard off, a SIGTERM cannot end the blocked loop: the stop grace ends the process.
  const int deaf_pipe_fd = OpenUnreadPipe(dir_ + "/deaf_trace");
  ASSERT_GE(deaf_pipe_fd, 0) << std::strerror(errno);
  Process& deaf = StartPolarimeter({"--rate-hz", "2000", "--trace", dir_ + "/deaf_trace", "--stuck-exit-s", "0"},
                                   "polarimeter_deaf");
  ASSERT_TRUE(Eventually([&] { return deaf.Log().find("real time at") != std::string::npos; }, 20s)) << deaf.Log();
  std::this_thread::sleep_for(1s);  // the pipe is full by now
  deaf.Signal(SIGTERM);
  const auto stop_code = deaf.Wait(30s);
  close(pipe_fd);
  close(deaf_pipe_fd);
  ASSERT_TRUE(stop_code.has_value()) << "SIGTERM did not end it: " << deaf.Log();
  EXPECT_EQ(*stop_code, 1) << deaf.Log();
  EXPECT_NE(deaf.Log().find("did not end within 8."), std::string::npos) << deaf.Log();
}

}  // namespace
}  // namespace dpc
