#include "dpc/instrument/line_link.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

namespace dpc::instrument {
namespace {

using Clock = std::chrono::steady_clock;

/// A listening TCP socket on 127.0.0.1 (an ephemeral port) whose accepted connection the test
/// drives by hand.
class TcpPeer {
 public:
  TcpPeer() {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    EXPECT_EQ(::listen(listener_, 4), 0);
    socklen_t length = sizeof address;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);
  }
  ~TcpPeer() {
    if (peer_ >= 0) ::close(peer_);
    ::close(listener_);
  }
  int port() const { return port_; }
  void Accept() { peer_ = ::accept(listener_, nullptr, nullptr); }
  void Send(const std::string& bytes) { EXPECT_EQ(::send(peer_, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size())); }
  /// One line the link sent (without "\n"), within a second.
  std::string ReceiveLine() {
    std::string line;
    char c = 0;
    while (true) {
      pollfd p{peer_, POLLIN, 0};
      if (::poll(&p, 1, 1000) <= 0 || ::read(peer_, &c, 1) != 1) return line + "<timeout>";
      if (c == '\n') return line;
      line += c;
    }
  }
  void Hangup() {
    ::close(peer_);
    peer_ = -1;
  }

 private:
  int listener_ = -1, peer_ = -1, port_ = 0;
};

InstrumentLinkConfig Tcp(int port) {
  InstrumentLinkConfig config;
  config.kind = InstrumentLinkConfig::Kind::kTcp;
  config.host = "127.0.0.1";
  config.port = port;
  return config;
}

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

TEST(LineLinkTest, QueriesAnInstrumentOverTcpLineByLine) {
  TcpPeer peer;
  LineLink link(Tcp(peer.port()));
  ASSERT_EQ(link.Open(1.0), "");
  peer.Accept();
  EXPECT_EQ(link.Describe(), "tcp 127.0.0.1:" + std::to_string(peer.port()));
  std::thread answer([&] {
    EXPECT_EQ(peer.ReceiveLine(), "*IDN?");
    peer.Send("dpc,EPC,3,0.1\r\n");
  });
  std::string why;
  const auto reply = link.Query("*IDN?", 1.0, &why);
  answer.join();
  ASSERT_TRUE(reply.has_value()) << why;
  EXPECT_EQ(*reply, "dpc,EPC,3,0.1");
}

TEST(LineLinkTest, ASilentInstrumentCostsNoMoreThanTheTimeout) {
  TcpPeer peer;
  LineLink link(Tcp(peer.port()));
  ASSERT_EQ(link.Open(1.0), "");
  peer.Accept();
  std::string why;
  const auto started = Clock::now();
  EXPECT_FALSE(link.Query(":MEAS:SOP?", 0.05, &why).has_value());
  EXPECT_LT(Seconds(Clock::now() - started), 0.5);
  EXPECT_NE(why.find("no reply within 0.05 s"), std::string::npos) << why;
  EXPECT_TRUE(link.is_open());
  // The late reply to that query is not taken for the answer to the next one.
  EXPECT_EQ(peer.ReceiveLine(), ":MEAS:SOP?");
  peer.Send("0,0,1\n");
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::thread answer([&] {
    EXPECT_EQ(peer.ReceiveLine(), ":MEAS:SOP?");
    peer.Send("1,0,0\n");
  });
  const auto reply = link.Query(":MEAS:SOP?", 1.0, &why);
  answer.join();
  ASSERT_TRUE(reply.has_value()) << why;
  EXPECT_EQ(*reply, "1,0,0");
}

TEST(LineLinkTest, AnEndlessLineIsRefusedAndTheNextLineStillReads) {
  TcpPeer peer;
  LineLink link(Tcp(peer.port()));
  ASSERT_EQ(link.Open(1.0), "");
  peer.Accept();
  peer.Send(std::string(5000, 'x'));
  std::string why;
  EXPECT_FALSE(link.ReadLine(0.2, &why).has_value());
  EXPECT_NE(why.find("longer than 256 bytes"), std::string::npos) << why;
  peer.Send(std::string(100, 'y') + "\nOK\n");
  why.clear();
  const auto line = link.ReadLine(1.0, &why);
  ASSERT_TRUE(line.has_value()) << why;
  EXPECT_EQ(*line, "OK");
}

TEST(LineLinkTest, AClosedConnectionOrARefusedOneIsSaidAndClosesTheLink) {
  TcpPeer peer;
  LineLink link(Tcp(peer.port()));
  ASSERT_EQ(link.Open(1.0), "");
  peer.Accept();
  peer.Hangup();
  std::string why;
  EXPECT_FALSE(link.ReadLine(1.0, &why).has_value());
  EXPECT_NE(why.find("closed the connection"), std::string::npos) << why;
  EXPECT_FALSE(link.is_open());
  EXPECT_NE(link.WriteLine("x", 0.1), "");
  // Nothing listens on the port of a closed listener.
  int port = 0;
  {
    TcpPeer gone;
    port = gone.port();
  }
  LineLink refused(Tcp(port));
  EXPECT_NE(refused.Open(1.0).find("connect"), std::string::npos);
}

TEST(LineLinkTest, ASerialPortIsOpenedRawAtItsBaudRate) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(grantpt(master), 0);
  ASSERT_EQ(unlockpt(master), 0);
  InstrumentLinkConfig config;
  config.kind = InstrumentLinkConfig::Kind::kSerial;
  config.path = ptsname(master);
  config.baud = 115200;
  LineLink link(config);
  ASSERT_EQ(link.Open(1.0), "") << config.path;
  EXPECT_EQ(link.Describe(), "serial " + config.path + " at 115200 Bd");
  std::thread answer([&] {
    std::string line;
    char c = 0;
    while (::read(master, &c, 1) == 1 && c != '\n') line += c;
    EXPECT_EQ(line, ":SOUR2:VOLT 1.2500");
    const std::string ok = "OK\n";
    EXPECT_EQ(::write(master, ok.data(), ok.size()), 3);
  });
  std::string why;
  const auto reply = link.Query(":SOUR2:VOLT 1.2500", 1.0, &why);
  answer.join();
  ASSERT_TRUE(reply.has_value()) << why;
  EXPECT_EQ(*reply, "OK");
  link.Close();
  ::close(master);
  config.path = "/dev/no-such-tty";
  LineLink missing(config);
  EXPECT_NE(missing.Open(1.0).find("/dev/no-such-tty"), std::string::npos);
}

TEST(ParseStokesReplyTest, TakesUnitOrPartlyPolarizedTriplesAndNormalizesThem) {
  StokesVector s[2];
  EXPECT_EQ(ParseStokesReply("0.000000,0.600000,0.800000", 1, 0.1, s), "");
  EXPECT_TRUE(s[0].isApprox(StokesVector(0, 0.6, 0.8)));
  EXPECT_EQ(ParseStokesReply(" 0.5, 0, 0 ", 1, 0.1, s), "");  // DOP 0.5
  EXPECT_TRUE(s[0].isApprox(StokesVector::UnitX()));
  EXPECT_EQ(ParseStokesReply("1,0,0,0,0,-1", 2, 0.1, s), "");
  EXPECT_TRUE(s[1].isApprox(-StokesVector::UnitZ()));
  EXPECT_NE(ParseStokesReply("1,0,0", 2, 0.1, s).find("3 numbers"), std::string::npos);
  EXPECT_NE(ParseStokesReply("1,0,0,0", 1, 0.1, s).find("4 numbers"), std::string::npos);
  EXPECT_NE(ParseStokesReply("1,nan,0", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply("1,inf,0", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply("1e400,0,0", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply("0.01,0,0", 1, 0.1, s).find("degree of polarization"), std::string::npos);
  EXPECT_NE(ParseStokesReply("2,0,0", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply("OK", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply("", 1, 0.1, s), "");
  EXPECT_NE(ParseStokesReply(std::string(300, ','), 1, 0.1, s), "");
}

TEST(ParseNumberReplyTest, OneFiniteNumberAlone) {
  double v = 0;
  EXPECT_EQ(ParseNumberReply("1.250000", &v), "");
  EXPECT_DOUBLE_EQ(v, 1.25);
  EXPECT_NE(ParseNumberReply("1.25 V", &v), "");
  EXPECT_NE(ParseNumberReply("nan", &v), "");
  EXPECT_NE(ParseNumberReply("", &v), "");
}

TEST(QuantizeTest, CodesOverTheFullScale) {
  const DacPoint zero = Quantize(0.0, -10.0, 10.0, 16);
  EXPECT_EQ(zero.code, 32768);  // 0 V lies between codes 32767 and 32768: the nearer
  EXPECT_NEAR(zero.volts, 0.0, 20.0 / 65535);
  EXPECT_EQ(Quantize(-10.0, -10.0, 10.0, 16).code, 0);
  EXPECT_EQ(Quantize(10.0, -10.0, 10.0, 16).code, 65535);
  EXPECT_DOUBLE_EQ(Quantize(10.0, -10.0, 10.0, 16).volts, 10.0);
  EXPECT_EQ(Quantize(99.0, -10.0, 10.0, 16).code, 65535);  // clamped into the full scale
  const DacPoint coarse = Quantize(1.0, 0.0, 3.0, 2);  // 4 codes: 0, 1, 2, 3 V
  EXPECT_EQ(coarse.code, 1);
  EXPECT_DOUBLE_EQ(coarse.volts, 1.0);
  EXPECT_DOUBLE_EQ(Quantize(1.4, 0.0, 3.0, 2).volts, 1.0);
  EXPECT_DOUBLE_EQ(Quantize(1.2345, -10.0, 10.0, 0).volts, 1.2345);
}

}  // namespace
}  // namespace dpc::instrument
