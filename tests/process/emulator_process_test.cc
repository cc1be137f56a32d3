// dpc-emulator as a lab runs it: the built binary on 127.0.0.1 with free ports (port 0), its
// start-up JSON line read from stdout, both instruments and the control port over TCP, both
// instruments on pseudo-terminals (--pty) opened as serial ports, faults taking an instrument
// away and giving it back, and SIGTERM → exit 0. Waits poll for a condition with a deadline;
// the only fixed wait is the one that checks that nothing comes.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "support/process.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using dpc::testing::Eventually;
using dpc::testing::Process;

/// A line-oriented client of one instrument: a TCP connection to 127.0.0.1, or a pseudo-
/// terminal's slave opened as a serial port.
class LineClient {
 public:
  static std::unique_ptr<LineClient> Tcp(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(static_cast<uint16_t>(port));
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      ::close(fd);
      return nullptr;
    }
    return std::unique_ptr<LineClient>(new LineClient(fd));
  }
  static std::unique_ptr<LineClient> Serial(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) return nullptr;
    termios mode{};
    ::tcgetattr(fd, &mode);
    ::cfmakeraw(&mode);
    ::cfsetspeed(&mode, B115200);
    ::tcsetattr(fd, TCSANOW, &mode);
    ::tcflush(fd, TCIOFLUSH);  // as a serial client does: nothing stale from before
    return std::unique_ptr<LineClient>(new LineClient(fd));
  }
  ~LineClient() { ::close(fd_); }

  bool Send(const std::string& line) {
    const std::string bytes = line + "\r\n";
    return ::write(fd_, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
  }
  /// The next line (without "\n"), or nullopt after `timeout` or at the end of the stream.
  std::optional<std::string> ReadLine(std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (const size_t newline = buffer_.find('\n'); newline != std::string::npos) {
        std::string line = buffer_.substr(0, newline);
        buffer_.erase(0, newline + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0 || closed_) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char chunk[4096];
      const ssize_t n = ::read(fd_, chunk, sizeof chunk);
      if (n <= 0) {
        closed_ = true;
        continue;
      }
      buffer_.append(chunk, static_cast<size_t>(n));
    }
  }
  std::optional<std::string> Ask(const std::string& line) {
    if (!Send(line)) return std::nullopt;
    return ReadLine();
  }
  /// Whether the emulator closed the connection (reads to the end, within `timeout`).
  bool ClosedWithin(std::chrono::milliseconds timeout) {
    while (!closed_ && ReadLine(timeout)) {
    }
    return closed_;
  }

 private:
  explicit LineClient(int fd) : fd_(fd) {}
  int fd_;
  std::string buffer_;
  bool closed_ = false;
};

std::vector<double> Numbers(const std::string& reply) {
  std::vector<double> values;
  std::stringstream in(reply);
  std::string field;
  while (std::getline(in, field, ',')) values.push_back(std::stod(field));
  return values;
}

class EmulatorProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dpc_emulator_process_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::unique_ptr<Process> Start(std::vector<std::string> args, const std::string& tag = "emulator") {
    args.insert(args.begin(), DPC_EMULATOR_BINARY);
    return std::make_unique<Process>(std::move(args), dir_ / (tag + ".out"), dir_ / (tag + ".err"));
  }
  /// The start-up line: the first line of stdout, once it is complete.
  static nlohmann::json Ready(Process& emulator) {
    std::string out;
    Eventually(
        [&] {
          out = emulator.out();
          return out.find('\n') != std::string::npos || !emulator.running();
        },
        10s);
    const size_t newline = out.find('\n');
    if (newline == std::string::npos) return nlohmann::json();
    return nlohmann::json::parse(out.substr(0, newline), nullptr, false);
  }

  fs::path dir_;
};

TEST_F(EmulatorProcessTest, ServesBothInstrumentsOverTcpAndPseudoTerminalsAndEndsCleanlyOnSigterm) {
  const auto emulator = Start({"--tcp-port-epc", "0", "--tcp-port-polarimeter", "0", "--control-port", "0", "--pty",
                               "--dac-bits", "12", "--noise-deg", "0.01"});
  const nlohmann::json ready = Ready(*emulator);
  ASSERT_TRUE(ready.is_object()) << emulator->Log();
  for (const char* key : {"epc_tcp", "polarimeter_tcp", "control_tcp"}) {
    ASSERT_TRUE(ready[key].is_number_integer()) << ready;
    EXPECT_GT(ready[key].get<int>(), 0);
  }
  EXPECT_NE(ready["epc_tcp"], ready["polarimeter_tcp"]);
  ASSERT_TRUE(ready["epc_pty"].is_string() && ready["polarimeter_pty"].is_string()) << ready;
  EXPECT_EQ(ready["epc_pty"].get<std::string>().rfind("/dev/pts/", 0), 0u) << ready;

  // The EPC over TCP: 12 bits over ±10 V put 5 V on the code at 4.998779 V.
  auto epc = LineClient::Tcp(ready["epc_tcp"].get<int>());
  ASSERT_TRUE(epc);
  EXPECT_EQ(epc->Ask("*IDN?"), "dpc-emulator,EPC,3,0.1");
  EXPECT_EQ(epc->Ask(":SOUR2:VOLT 5"), "OK");
  EXPECT_EQ(epc->Ask(":SOUR2:VOLT?"), "4.998779");
  EXPECT_EQ(epc->Ask(":SOUR2:VOLT 11"), "ERR 11 V is outside the full scale [-10, 10] V");
  EXPECT_EQ(epc->Ask(":SOUR9:VOLT?"), "ERR unknown channel 9 (channels 1-3)");

  // The polarimeter over TCP.
  auto polarimeter = LineClient::Tcp(ready["polarimeter_tcp"].get<int>());
  ASSERT_TRUE(polarimeter);
  EXPECT_EQ(polarimeter->Ask("*IDN?"), "dpc-emulator,POL,0,0.1");
  const std::optional<std::string> both = polarimeter->Ask(":MEAS:BOTH?");
  ASSERT_TRUE(both);
  const std::vector<double> v = Numbers(*both);
  ASSERT_EQ(v.size(), 6u) << *both;
  EXPECT_NEAR(std::hypot(v[0], v[1], v[2]), 1.0, 1e-5) << *both;
  EXPECT_NEAR(std::hypot(v[3], v[4], v[5]), 1.0, 1e-5) << *both;

  // Both instruments on their pseudo-terminals, the same device as over TCP.
  auto serial_epc = LineClient::Serial(ready["epc_pty"].get<std::string>());
  auto serial_polarimeter = LineClient::Serial(ready["polarimeter_pty"].get<std::string>());
  ASSERT_TRUE(serial_epc && serial_polarimeter);
  EXPECT_EQ(serial_polarimeter->Ask("*IDN?"), "dpc-emulator,POL,0,0.1");
  const std::vector<double> sop = Numbers(serial_polarimeter->Ask(":MEAS:SOP?").value_or(""));
  ASSERT_EQ(sop.size(), 3u);
  EXPECT_NEAR(std::hypot(sop[0], sop[1], sop[2]), 1.0, 1e-5);
  EXPECT_EQ(serial_epc->Ask(":SOUR2:VOLT?"), "4.998779");
  EXPECT_EQ(serial_epc->Ask(":SOUR1:VOLT -3"), "OK");
  EXPECT_EQ(epc->Ask(":SOUR1:VOLT?"), "-3.001221");  // the code nearest -3 V

  // The control port sees it all.
  auto control = LineClient::Tcp(ready["control_tcp"].get<int>());
  ASSERT_TRUE(control);
  const nlohmann::json status = nlohmann::json::parse(control->Ask("status").value_or(""), nullptr, false);
  ASSERT_TRUE(status.is_object()) << emulator->Log();
  EXPECT_NEAR(status["channels"][1]["set_v"].get<double>(), -10.0 + 3071 * 20.0 / 4095, 1e-12) << status;
  EXPECT_NEAR(status["channels"][0]["set_v"].get<double>(), -10.0 + 1433 * 20.0 / 4095, 1e-12) << status;
  EXPECT_EQ(status["epc"]["sets"], 2) << status;
  EXPECT_EQ(status["epc"]["connections"]["open"], 2) << status;  // TCP and the pseudo-terminal
  EXPECT_EQ(status["polarimeter"]["queries"], 4) << status;

  // Faults: the next polarimeter reply garbage, then one cut in half.
  EXPECT_EQ(control->Ask("garbage polarimeter 1"), "OK garbage polarimeter: the next 1 reply");
  EXPECT_EQ(control->Ask("truncate polarimeter 1"), "OK truncate polarimeter: the next 1 reply");
  const std::optional<std::string> junk = polarimeter->Ask("*IDN?");
  ASSERT_TRUE(junk);
  EXPECT_EQ(junk->find("dpc"), std::string::npos) << *junk;
  polarimeter->Send("*IDN?");
  EXPECT_EQ(polarimeter->Ask("*IDN?"), "dpc-emulatodpc-emulator,POL,0,0.1");  // the half, then a whole reply

  // disconnect: the EPC's TCP client is closed, a new one refused, the pseudo-terminal silent;
  // once the time is up both answer again.
  EXPECT_EQ(control->Ask("disconnect epc 2").value_or("").rfind("OK disconnect epc: 2 sessions ended", 0), 0u);
  EXPECT_TRUE(epc->ClosedWithin(5s));
  auto refused = LineClient::Tcp(ready["epc_tcp"].get<int>());
  ASSERT_TRUE(refused);  // the kernel completes the handshake; the emulator closes at once
  EXPECT_TRUE(refused->ClosedWithin(5s));
  serial_epc->Send("*IDN?");
  EXPECT_EQ(serial_epc->ReadLine(300ms), std::nullopt);
  EXPECT_EQ(polarimeter->Ask("*IDN?"), "dpc-emulator,POL,0,0.1");
  std::unique_ptr<LineClient> back;
  ASSERT_TRUE(Eventually(
      [&] {
        back = LineClient::Tcp(ready["epc_tcp"].get<int>());
        return back && back->Ask("*IDN?") == "dpc-emulator,EPC,3,0.1";
      },
      10s));
  ASSERT_TRUE(Eventually([&] { return serial_epc->Ask("*IDN?") == "dpc-emulator,EPC,3,0.1"; }, 10s));

  // powercycle: every voltage forgotten.
  EXPECT_EQ(control->Ask("powercycle 0.2").value_or("").rfind("OK powercycle: every channel at 0 V", 0), 0u);
  EXPECT_TRUE(back->ClosedWithin(5s));
  ASSERT_TRUE(Eventually(
      [&] {
        back = LineClient::Tcp(ready["epc_tcp"].get<int>());
        return back && back->Ask(":SOUR2:VOLT?") == "0.000000";
      },
      10s));
  EXPECT_EQ(control->Ask("temperature 40"), "OK temperature 40 C");
  EXPECT_EQ(nlohmann::json::parse(control->Ask("status").value_or("{}"))["temperature_c"], 40.0);

  emulator->Signal(SIGTERM);
  EXPECT_EQ(emulator->Wait(10s), 0) << emulator->Log();
  EXPECT_NE(emulator->err().find("stopped on signal 15"), std::string::npos) << emulator->err();
}

TEST_F(EmulatorProcessTest, RefusesBadOptionsAndScenariosAndAPortInUse) {
  const auto code = [&](std::vector<std::string> args, const std::string& tag) {
    auto process = Start(std::move(args), tag);
    const std::optional<int> exit = process->Wait(20s);
    return std::make_pair(exit.value_or(-1), process->err());
  };
  auto [bits, bits_log] = code({"--dac-bits", "0", "--control-port", "0", "--tcp-port-epc", "0",
                                "--tcp-port-polarimeter", "0"},
                               "bits");
  EXPECT_EQ(bits, 2) << bits_log;
  EXPECT_NE(bits_log.find("--dac-bits: 0 is not in [1, 32]"), std::string::npos) << bits_log;
  auto [rate, rate_log] = code({"--sample-rate-hz", "5e7", "--delay-s", "2e-8", "--control-port", "0",
                                "--tcp-port-epc", "0", "--tcp-port-polarimeter", "0"},
                               "rate");
  EXPECT_EQ(rate, 2) << rate_log;
  EXPECT_NE(rate_log.find("simulation.sample_rate_hz"), std::string::npos) << rate_log;
  EXPECT_NE(rate_log.find("(set by --sample-rate-hz)"), std::string::npos) << rate_log;

  // Its help speaks of no DDS participant, which it does not have (but for the version of the library linked).
  auto help = Start({"--help"}, "help");
  EXPECT_EQ(help->Wait(20s), 0) << help->err();
  const std::string help_text = help->out();
  EXPECT_NE(help_text.find("when the emulator's loop has not turned"), std::string::npos) << help_text;
  EXPECT_EQ(help_text.find("participant"), std::string::npos) << help_text;

  // A port another emulator holds: cannot start (4), naming the option.
  const auto first = Start({"--tcp-port-epc", "0", "--tcp-port-polarimeter", "0", "--control-port", "0"}, "first");
  const nlohmann::json ready = Ready(*first);
  ASSERT_TRUE(ready.is_object()) << first->Log();
  const std::string taken = std::to_string(ready["epc_tcp"].get<int>());
  auto [busy, busy_log] = code({"--tcp-port-epc", "0", "--tcp-port-polarimeter", taken, "--control-port", "0"}, "busy");
  EXPECT_EQ(busy, 4) << busy_log;
  EXPECT_NE(busy_log.find("--tcp-port-polarimeter " + taken + ": bind 127.0.0.1:" + taken), std::string::npos)
      << busy_log;
  // SIGINT ends it as cleanly as SIGTERM.
  first->Signal(SIGINT);
  EXPECT_EQ(first->Wait(10s), 0) << first->Log();
}

TEST_F(EmulatorProcessTest, ListensOnLoopbackOnly) {
  const auto emulator = Start({"--tcp-port-epc", "0", "--tcp-port-polarimeter", "0", "--control-port", "0"});
  const nlohmann::json ready = Ready(*emulator);
  ASSERT_TRUE(ready.is_object()) << emulator->Log();
  // Every listening socket of the process is bound to 127.0.0.1 (/proc/net/tcp: local address
  // 0100007F, state 0A = LISTEN), none to another address.
  std::ifstream tcp("/proc/net/tcp");
  std::string line;
  int loopback = 0;
  std::getline(tcp, line);
  while (std::getline(tcp, line)) {
    std::istringstream fields(line);
    std::string slot, local, remote, state;
    fields >> slot >> local >> remote >> state;
    if (state != "0A") continue;
    const int port = std::stoi(local.substr(local.find(':') + 1), nullptr, 16);
    for (const char* key : {"epc_tcp", "polarimeter_tcp", "control_tcp"}) {
      if (port != ready[key].get<int>()) continue;
      EXPECT_EQ(local.substr(0, local.find(':')), "0100007F") << line;
      ++loopback;
    }
  }
  EXPECT_EQ(loopback, 3);
}

}  // namespace
