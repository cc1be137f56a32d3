// End-to-end tests of the DDS tools of `dpc` (topic list/echo/hz, target, monitor) against a
// real bench: dpc-driver, dpc-controller and dpc-polarimeter started as processes on a private
// DDS domain (80–99) with the loopback-only profile. Every process a test starts is stopped
// (SIGINT, then SIGKILL) and reaped by RAII, also when the test fails. Waits poll for a
// condition with a deadline; nothing relies on a fixed sleep.

#include <fcntl.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/bench_tools_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

/// `dpc <args>` on a pseudo-terminal of `columns` columns (as a person's terminal would run
/// it); everything it wrote, until it exits (at most `timeout`).
std::string OnTerminal(std::vector<std::string> args, int columns, std::chrono::milliseconds timeout) {
  args.insert(args.begin(), DPC_BINARY);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  winsize size{};
  size.ws_row = 24;
  size.ws_col = static_cast<unsigned short>(columns);
  int master = -1;
  const pid_t pid = forkpty(&master, nullptr, nullptr, &size);
  if (pid < 0) return "forkpty failed";
  if (pid == 0) {
    unsetenv("COLUMNS");
    execv(argv[0], argv.data());
    _exit(127);
  }
  std::string out;
  const auto end = std::chrono::steady_clock::now() + timeout;
  char buffer[4096];
  fcntl(master, F_SETFL, O_NONBLOCK);
  while (std::chrono::steady_clock::now() < end) {
    const ssize_t n = read(master, buffer, sizeof buffer);
    if (n > 0) {
      out.append(buffer, static_cast<size_t>(n));
    } else if (n == 0 || (n < 0 && errno != EAGAIN)) {
      break;  // EIO: the child closed the terminal (exited)
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  kill(pid, SIGKILL);  // no-op if it exited
  waitpid(pid, nullptr, 0);
  close(master);
  return out;
}

/// Code points of UTF-8 text.
size_t Width(const std::string& text) {
  size_t width = 0;
  for (unsigned char c : text) width += (c & 0xC0) != 0x80;
  return width;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) out.push_back(line);
  }
  return out;
}

using dpc::testing::Eventually;
using dpc::testing::Process;
using dpc::testing::Result;
using dpc::testing::Slurp;

using DpcTopicToolsTest = dpc::testing::BenchToolsTest;

// ---- no bench needed

TEST_F(DpcTopicToolsTest, UnknownTopicExits2AndListsTheValidOnes) {
  for (const char* command : {"echo", "hz"}) {
    const Result r = Dpc({"topic", command, "no_such_topic", "--domain", "90", "--timeout-s", "1"});
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    EXPECT_NE(r.err.find("unknown topic \"no_such_topic\""), std::string::npos) << r.err;
    for (const char* topic : {"dpc_stokes_sample", "dpc_waveplate_command", "dpc_waveplate_state",
                              "dpc_controller_status", "dpc_device_description", "dpc_target",
                              "dpc_target_request", "dpc_target_reply"}) {
      EXPECT_NE(r.err.find(topic), std::string::npos) << command << " " << topic << "\n" << r.err;
    }
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

TEST_F(DpcTopicToolsTest, EchoAndHzTimeOutWithExit3WhenNothingArrives) {
  const Result echo = Dpc({"topic", "echo", "dpc_waveplate_state", "--domain", "91", "--timeout-s", "1"});
  EXPECT_EQ(echo.exit_code, 3) << echo.err;
  EXPECT_NE(echo.err.find("no sample on dpc_waveplate_state"), std::string::npos) << echo.err;
  const Result hz = Dpc({"topic", "hz", "sample", "--domain", "91", "--timeout-s", "1"});
  EXPECT_EQ(hz.exit_code, 3) << hz.err;
  EXPECT_NE(hz.err.find("no sample on dpc_stokes_sample"), std::string::npos) << hz.err;
}

TEST_F(DpcTopicToolsTest, TargetWithoutDriverTimesOutWithExit1) {
  const Result r = Dpc({"target", "--point", "0", "0", "1", "--domain", "92", "--timeout-s", "1"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("no driver on domain 92"), std::string::npos) << r.err;
}

TEST_F(DpcTopicToolsTest, BadCommandLinesExit2NamingTheFlag) {
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"target", "--point", "1", "1", "0"}, "--point: "},
      {{"target", "--point", "0", "0", "0.9"}, "--point: "},
      {{"target", "--point", "nan", "0", "1"}, "--point: "},
      {{"target", "--set-normal", "0", "0", "1", "--offset", "1.5"}, "--offset: "},
      {{"target", "--set-normal", "0", "0", "0"}, "--set-normal: "},
      {{"target"}, "give the new target"},
      {{"target", "--point", "0", "0", "1", "--linear"}, "excludes"},
      {{"target", "--point", "0", "0", "1", "--bench-id", "*"}, "--bench-id"},
      {{"monitor", "--bench-id", "*"}, "--bench-id"},
      {{"topic", "echo", "state", "--domain", "300"}, "--domain"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    if (std::find(args.begin(), args.end(), "--domain") == args.end()) {
      args.insert(args.end(), {"--domain", "93"});
    }
    const Result r = Dpc(args);
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    EXPECT_EQ(r.exit_code, 2) << joined << "\n" << r.err;
    EXPECT_NE((r.err + r.out).find(c.expected), std::string::npos) << joined << "\n" << r.err << r.out;
  }
}

// ---- against a running bench

TEST_F(DpcTopicToolsTest, TopicListShowsTheBenchTopicsWithWritersAndReaders) {
  StartBench(81);
  std::string out;
  const std::regex sample_row(R"(dpc_stokes_sample\s+dpc::msg::StokesSample\s+(\d+)\s+(\d+))");
  const std::regex state_row(R"(dpc_waveplate_state\s+dpc::msg::WaveplateState\s+(\d+)\s+(\d+))");
  std::smatch m;
  const bool listed = Eventually(
      [&] {
        const Result r = Dpc({"topic", "list", "--domain", "81", "--wait-s", "1.5"});
        EXPECT_EQ(r.exit_code, 0) << r.err;
        out = r.out;
        for (const char* topic : {"dpc_stokes_sample", "dpc_waveplate_command", "dpc_waveplate_state",
                                  "dpc_controller_status", "dpc_device_description", "dpc_target",
                                  "dpc_target_request", "dpc_target_reply"}) {
          if (out.find(topic) == std::string::npos) return false;
        }
        // Samples: the polarimeter writes; the controller reads (at least).
        return std::regex_search(out, m, sample_row) && std::stoi(m[1]) == 1 && std::stoi(m[2]) >= 1;
      },
      30000ms);
  ASSERT_TRUE(listed) << out;
  ASSERT_TRUE(std::regex_search(out, m, state_row)) << out;
  EXPECT_EQ(std::stoi(m[1]), 1) << out;   // the driver
  EXPECT_GE(std::stoi(m[2]), 2) << out;   // controller and polarimeter
  EXPECT_NE(out.find("dpc-driver/bench1"), std::string::npos) << out;
  EXPECT_NE(out.find("dpc-controller/A"), std::string::npos) << out;
  // A topic nobody uses here does not appear.
  EXPECT_EQ(out.find("rt/"), std::string::npos) << out;
}

TEST_F(DpcTopicToolsTest, EchoStateJsonPrintsCompleteObjects) {
  StartBench(82);
  const Result r = Dpc({"topic", "echo", "state", "--json", "--count", "3", "--timeout-s", "20",
                        "--domain", "82"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = Lines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  uint64_t previous = 0;
  for (const std::string& line : lines) {
    const auto j = nlohmann::json::parse(line);  // throws (fails the test) if not JSON
    for (const char* key : {"bench_id", "sequence_number", "answers_sample", "sample_time_ns",
                            "sample_publish_time_ns", "command_receive_time_ns", "publish_time_ns",
                            "phi_applied", "phi_rate_per_s", "ramp_start_time_ns",
                            "ramp_end_time_ns", "saturated", "mode", "reason", "obeyed_controller_id",
                            "obeyed_priority", "commands_applied", "commands_rejected",
                            "commands_limited", "controller_switches", "last_rejection",
                            "applied_controller_id", "stand_ins"}) {
      EXPECT_TRUE(j.contains(key)) << key << " missing in " << line;
    }
    EXPECT_EQ(j.size(), 23u) << line;
    EXPECT_EQ(j["bench_id"], "bench1");
    ASSERT_TRUE(j["phi_applied"].is_array());
    EXPECT_EQ(j["phi_applied"].size(), 3u) << line;  // the default bench: 3 stages
    EXPECT_EQ(j["saturated"].size(), 3u) << line;
    EXPECT_TRUE(j["mode"] == "DRIVER_ACTIVE" || j["mode"] == "DRIVER_HOLDING") << line;
    const uint64_t sequence = j["sequence_number"].get<uint64_t>();
    EXPECT_GT(sequence, previous) << line;
    previous = sequence;
  }
  // The readable form: one line per sample, with the mode and units.
  const Result text = Dpc({"topic", "echo", "dpc_waveplate_state", "--count", "2", "--timeout-s", "20",
                           "--domain", "82"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  const auto text_lines = Lines(text.out);
  ASSERT_EQ(text_lines.size(), 2u) << text.out;
  EXPECT_NE(text_lines[0].find("[bench1] state #"), std::string::npos) << text.out;
  EXPECT_NE(text_lines[0].find("phi_applied=["), std::string::npos) << text.out;
  // Another bench id sees nothing.
  const Result other = Dpc({"topic", "echo", "state", "--bench-id", "bench2", "--timeout-s", "1.5",
                            "--domain", "82"});
  EXPECT_EQ(other.exit_code, 3) << other.out << other.err;
  EXPECT_TRUE(other.out.empty()) << other.out;
}

TEST_F(DpcTopicToolsTest, HzOfSamplesIsNearThePolarimeterRate) {
  StartBench(83, 200);
  const Result r = Dpc({"topic", "hz", "sample", "--window-s", "1", "--count-windows", "3", "--json",
                        "--timeout-s", "20", "--domain", "83"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = Lines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  double rate_sum_hz = 0;
  for (size_t i = 1; i < lines.size(); ++i) {  // the first window may see discovery effects
    const auto j = nlohmann::json::parse(lines[i]);
    EXPECT_EQ(j["topic"], "dpc_stokes_sample");
    const double rate_hz = j["rate_hz"].get<double>();
    rate_sum_hz += rate_hz;
    ASSERT_TRUE(j["interval_ms"].is_object()) << lines[i];
    const double min_ms = j["interval_ms"]["min"], mean_ms = j["interval_ms"]["mean"],
                 max_ms = j["interval_ms"]["max"];
    EXPECT_LE(min_ms, mean_ms);
    EXPECT_LE(mean_ms, max_ms);
    EXPECT_NEAR(mean_ms, 1000.0 / rate_hz, 0.5) << lines[i];
  }
  EXPECT_NEAR(rate_sum_hz / 2, 200.0, 40.0) << r.out;
  // The text form.
  const Result text = Dpc({"topic", "hz", "dpc_stokes_sample", "--window-s", "0.5", "--count-windows",
                           "1", "--timeout-s", "20", "--domain", "83"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_TRUE(std::regex_search(text.out, std::regex(R"(dpc_stokes_sample: rate_hz=\d+\.\d samples=\d+ window_s=0\.5 interval_ms min=[\d.]+ mean=[\d.]+ max=[\d.]+)")))
      << text.out;
}

TEST_F(DpcTopicToolsTest, TargetPointIsAcceptedAndPublishedAsTheNextRevision) {
  StartBench(84);
  // The scenario's target: the first revision of the driver's epoch (its start, in seconds).
  const Result before = Dpc({"topic", "echo", "target", "--json", "--count", "1", "--timeout-s", "20",
                             "--domain", "84"});
  ASSERT_EQ(before.exit_code, 0) << before.err;
  const uint64_t first = nlohmann::json::parse(before.out)["revision"].get<uint64_t>();
  EXPECT_EQ(first & 0xffffffffu, 1u) << before.out;
  EXPECT_GE(first >> 32, 1'700'000'000u) << before.out;

  const Result r = Dpc({"target", "--point", "0", "0", "1", "--domain", "84"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find(fmt::format("accepted: bench bench1 target revision {}: point [+0.0000, +0.0000, +1.0000]",
                                   first + 1)),
            std::string::npos)
      << r.out;
  const std::smatch m = [&] {
    std::smatch match;
    std::regex_search(r.out, match, std::regex(R"(request (dpc-target-\d+-\d+))"));
    return match;
  }();
  ASSERT_EQ(m.size(), 2u) << r.out;
  const std::string request_id = m[1];

  const Result after = Dpc({"topic", "echo", "target", "--json", "--count", "1", "--timeout-s", "20",
                            "--domain", "84"});
  ASSERT_EQ(after.exit_code, 0) << after.err;
  const auto j = nlohmann::json::parse(after.out);
  EXPECT_EQ(j["revision"].get<uint64_t>(), first + 1) << after.out;
  EXPECT_EQ(j["kind"], "TARGET_POINT") << after.out;
  EXPECT_EQ(j["request_id"], request_id) << after.out;
  ASSERT_EQ(j["point"].size(), 3u);
  EXPECT_DOUBLE_EQ(j["point"][0].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(j["point"][1].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(j["point"][2].get<double>(), 1.0);

  // A set target: the next.
  const Result linear = Dpc({"target", "--linear", "--domain", "84"});
  ASSERT_EQ(linear.exit_code, 0) << linear.err;
  EXPECT_NE(linear.out.find(fmt::format("revision {}: set [+0.0000, +0.0000, +1.0000]·S = 0.0000", first + 2)),
            std::string::npos)
      << linear.out;
}

TEST_F(DpcTopicToolsTest, InvalidTargetIsRefusedBeforeAnythingIsSent) {
  StartBench(85);
  AwaitObeyed(85, "A");
  const Result r = Dpc({"target", "--point", "1", "1", "0", "--domain", "85"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--point: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing sent"), std::string::npos) << r.err;
  // The driver saw no request: the target is still the scenario's, and it logged none.
  const Result target = Dpc({"topic", "echo", "target", "--json", "--count", "1", "--timeout-s", "20",
                             "--domain", "85"});
  ASSERT_EQ(target.exit_code, 0) << target.err;
  EXPECT_EQ(nlohmann::json::parse(target.out)["revision"].get<uint64_t>() & 0xffffffffu, 1u) << target.out;
  const std::string driver_log = Slurp(dir_ / "driver.err");
  EXPECT_EQ(driver_log.find("target request"), std::string::npos) << driver_log;
  EXPECT_EQ(driver_log.find("target revision"), std::string::npos) << driver_log;
}

TEST_F(DpcTopicToolsTest, MonitorLinesNameTheObeyedController) {
  StartBench(86);
  AwaitObeyed(86, "A");
  const Result r = Dpc({"monitor", "--lines", "--duration-s", "3", "--domain", "86"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = Lines(r.out);
  ASSERT_GE(lines.size(), 13u) << r.out;   // 5 Hz for 3 s
  ASSERT_LE(lines.size(), 17u) << r.out;
  // Until the monitor has discovered the target, state and sample writers (each in its own time),
  // its lines say what it has not seen yet; from the first complete line on, every line names the
  // obeyed controller, its error and the sample rate.
  const std::regex status(
      R"(^(?:LOCKED|LOST) [\d.]+ s \| error_deg ([\d.]+) \(max ([\d.]+)\) \| phi \[[-+\d., ]+\] \| rate_hz ([\d.]+) \| ACTIVE obeyed A \(priority 0\) \| missed_deadlines A=\d+ \| target r1$)");
  std::smatch m;
  size_t i = 1;  // the first may precede the first state
  while (i < lines.size() && !std::regex_match(lines[i], status)) {
    EXPECT_NE(lines[i].find("(no "), std::string::npos) << "incomplete but not waiting: " << lines[i];
    ++i;
  }
  const size_t first_with_samples = i;
  for (; i < lines.size(); ++i) {
    ASSERT_TRUE(std::regex_match(lines[i], m, status)) << lines[i] << "\n" << r.out;
    EXPECT_LE(std::stod(m[1]), std::stod(m[2])) << lines[i];
    EXPECT_LT(std::stod(m[2]), 180.0) << lines[i];
    // The rate is counted over each line's period: the first period with samples may be partial.
    if (i > first_with_samples) {
      EXPECT_GT(std::stod(m[3]), 50.0) << lines[i];   // 200 Hz polarimeter
      EXPECT_LT(std::stod(m[3]), 400.0) << lines[i];
    }
  }
  EXPECT_GE(lines.size() - first_with_samples, 7u) << "samples seen for less than 1.4 s\n" << r.out;
  EXPECT_EQ(r.out.find('\r'), std::string::npos) << "not a terminal: no redraw";
}

TEST_F(DpcTopicToolsTest, MonitorStopsCleanlyOnSigint) {
  StartBench(87);
  Process monitor({DPC_BINARY, "monitor", "--domain", "87", "--rate-hz", "10"}, dir_ / "monitor.out",
                  dir_ / "monitor.err");
  ASSERT_TRUE(Eventually([&] { return Lines(monitor.out()).size() >= 3; }, 20000ms)) << monitor.err();
  monitor.Signal(SIGINT);
  const auto code = monitor.Wait(10000ms);
  ASSERT_TRUE(code.has_value()) << "monitor ignored SIGINT";
  EXPECT_EQ(*code, 0) << monitor.err();
  EXPECT_NE(monitor.err().find("stopped by signal"), std::string::npos) << monitor.err();
}

TEST_F(DpcTopicToolsTest, MonitorOnATerminalOfEightyOrAHundredColumnsRedrawsOneLineThatNeverWraps) {
  StartBench(88);
  AwaitObeyed(88, "A");
  for (int columns : {80, 100}) {
    const std::string out =
        OnTerminal({"monitor", "--duration-s", "2.5", "--rate-hz", "10", "--domain", "88"}, columns, 20000ms);
    // What the terminal shows: each redraw is "\r<line>\x1b[K" (the terminal turns "\n" into
    // "\r\n"); the first line on stderr names the bench.
    std::vector<std::string> redraws;
    std::string current;
    for (size_t i = 0; i < out.size(); ++i) {
      if (out[i] == '\r' || out[i] == '\n') {
        if (!current.empty()) redraws.push_back(current);
        current.clear();
      } else if (out.compare(i, 3, "\x1b[K") == 0) {
        i += 2;
      } else {
        current += out[i];
      }
    }
    if (!current.empty()) redraws.push_back(current);
    ASSERT_GE(redraws.size(), 15u) << out;  // 10 Hz for 2.5 s, and the banner
    // At this bench's 200 Hz the error hovers around the 10° lock threshold: LOCKED or LOST.
    size_t tracking = 0;
    for (const auto& line : redraws) {
      EXPECT_LT(Width(line), static_cast<size_t>(columns)) << columns << " columns: " << line;
      if (line.rfind("LOCKED ", 0) == 0 || line.rfind("LOST ", 0) == 0) {
        ++tracking;
        EXPECT_NE(line.find(" | error "), std::string::npos) << line;
        EXPECT_NE(line.find(" | obeys A (p0) | "), std::string::npos) << line;
      }
    }
    EXPECT_GE(tracking, 10u) << out;
    std::printf("%d columns: %s\n", columns, redraws.back().c_str());
  }
}

}  // namespace
