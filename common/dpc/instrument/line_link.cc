#include "dpc/instrument/line_link.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <utility>

namespace dpc::instrument {
namespace {

using Clock = std::chrono::steady_clock;

Clock::time_point Deadline(double timeout_s) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, timeout_s)));
}

/// Milliseconds left until `deadline` for poll(), at least 0.
int MillisecondsLeft(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
  return left <= 0 ? 0 : static_cast<int>(std::min<int64_t>((left + 999) / 1000, 60'000));
}

speed_t BaudConstant(int baud) {
  switch (baud) {
    case 1200: return B1200;
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default: return B0;
  }
}

std::string Errno(const char* what) { return fmt::format("{}: {}", what, std::strerror(errno)); }

}  // namespace

LineLink::LineLink(InstrumentLinkConfig config, size_t max_line_bytes)
    : config_(std::move(config)), max_line_bytes_(max_line_bytes) {}

LineLink::~LineLink() { Close(); }

std::string LineLink::Describe() const {
  return config_.kind == InstrumentLinkConfig::Kind::kTcp
             ? fmt::format("tcp {}:{}", config_.host, config_.port)
             : fmt::format("serial {} at {} Bd", config_.path, config_.baud);
}

void LineLink::Close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  buffer_.clear();
  discarding_line_ = false;
}

std::string LineLink::Open(double timeout_s) {
  Close();
  return config_.kind == InstrumentLinkConfig::Kind::kTcp ? OpenTcp(timeout_s) : OpenSerial();
}

std::string LineLink::OpenTcp(double timeout_s) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(config_.port));
  if (inet_pton(AF_INET, config_.host.c_str(), &address.sin_addr) != 1) {
    return fmt::format("\"{}\" is not an IPv4 address", config_.host);
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return Errno("socket");
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // one short line per command
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0 && errno != EINPROGRESS) {
    const std::string why = Errno("connect");
    ::close(fd);
    return why;
  }
  pollfd p{fd, POLLOUT, 0};
  const int ready = ::poll(&p, 1, MillisecondsLeft(Deadline(timeout_s)));
  int error = 0;
  socklen_t length = sizeof error;
  if (ready <= 0) {
    ::close(fd);
    return ready == 0 ? fmt::format("connect: no answer within {:g} s", timeout_s) : Errno("poll");
  }
  if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) != 0 || error != 0) {
    ::close(fd);
    return fmt::format("connect: {}", std::strerror(error != 0 ? error : errno));
  }
  fd_ = fd;
  return {};
}

std::string LineLink::OpenSerial() {
  const int fd = ::open(config_.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return Errno(config_.path.c_str());
  termios tty{};
  if (tcgetattr(fd, &tty) != 0) {
    const std::string why = Errno("tcgetattr (not a terminal?)");
    ::close(fd);
    return why;
  }
  cfmakeraw(&tty);  // 8 data bits, no parity, no echo, no line editing
  tty.c_cflag |= CLOCAL | CREAD;
  tty.c_cflag &= ~(CSTOPB | CRTSCTS);
  cfsetispeed(&tty, BaudConstant(config_.baud));
  cfsetospeed(&tty, BaudConstant(config_.baud));
  if (tcsetattr(fd, TCSANOW, &tty) != 0) {
    const std::string why = Errno("tcsetattr");
    ::close(fd);
    return why;
  }
  tcflush(fd, TCIOFLUSH);
  fd_ = fd;
  return {};
}

std::string LineLink::WriteLine(const std::string& line, double timeout_s) {
  if (fd_ < 0) return "not connected";
  const std::string bytes = line + "\n";
  const auto deadline = Deadline(timeout_s);
  size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = config_.kind == InstrumentLinkConfig::Kind::kTcp
                          ? ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL)
                          : ::write(fd_, bytes.data() + sent, bytes.size() - sent);
    if (n > 0) {
      sent += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      const std::string why = Errno("write");
      Close();
      return why;
    }
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, MillisecondsLeft(deadline)) <= 0) {
      Close();
      return fmt::format("write: the instrument took no data for {:g} s", timeout_s);
    }
  }
  return {};
}

bool LineLink::Fill(double timeout_s, std::string* why) {
  pollfd p{fd_, POLLIN, 0};
  const int ready = ::poll(&p, 1, MillisecondsLeft(Deadline(timeout_s)));
  if (ready == 0) {
    *why = "no reply";
    return true;  // a timeout, not a closed link
  }
  char chunk[512];
  const ssize_t n = ::read(fd_, chunk, sizeof chunk);
  if (n > 0) {
    buffer_.append(chunk, static_cast<size_t>(n));
    return true;
  }
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return true;
  *why = n == 0 ? "the instrument closed the connection" : Errno("read");
  Close();
  return false;
}

std::optional<std::string> LineLink::ReadLine(double timeout_s, std::string* why) {
  return ReadLineBy(Deadline(timeout_s), timeout_s, why);
}

std::optional<std::string> LineLink::ReadLineBy(std::chrono::steady_clock::time_point deadline, double timeout_s,
                                                std::string* why) {
  for (;;) {
    if (fd_ < 0) {
      if (why->empty()) *why = "not connected";
      return std::nullopt;
    }
    const size_t end = buffer_.find('\n');
    if (discarding_line_) {
      if (end == std::string::npos) {
        buffer_.clear();
      } else {
        buffer_.erase(0, end + 1);
        discarding_line_ = false;
        continue;
      }
    } else if (end != std::string::npos) {
      std::string line = buffer_.substr(0, end);
      buffer_.erase(0, end + 1);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.size() > max_line_bytes_) {
        *why = fmt::format("a reply of {} bytes (at most {})", line.size(), max_line_bytes_);
        return std::nullopt;
      }
      return line;
    } else if (buffer_.size() > max_line_bytes_) {
      buffer_.clear();
      discarding_line_ = true;
      *why = fmt::format("a reply longer than {} bytes", max_line_bytes_);
      return std::nullopt;
    }
    if (Clock::now() >= deadline) {
      *why = fmt::format("no reply within {:.3g} s", timeout_s);
      return std::nullopt;
    }
    std::string fill_why;
    if (!Fill(std::chrono::duration<double>(deadline - Clock::now()).count(), &fill_why)) {
      *why = fill_why;
      return std::nullopt;
    }
  }
}

std::optional<std::string> LineLink::ReadNewestLine(double timeout_s, std::string* why, uint64_t* overtaken) {
  std::optional<std::string> line = ReadLine(timeout_s, why);
  if (!line) return line;
  // What is already here, without waiting; bounded, so that a flood cannot hold the caller.
  for (int i = 0; i < 64 && fd_ >= 0; ++i) {
    const size_t before = buffer_.size();
    std::string ignored;
    if (!Fill(0.0, &ignored) || buffer_.size() == before) break;
  }
  while (fd_ >= 0 && buffer_.find('\n') != std::string::npos) {
    std::string ignored;
    std::optional<std::string> newer = ReadLine(0.0, &ignored);
    if (!newer) continue;  // an over-long line, dropped: the one before stays the newest
    line = std::move(newer);
    ++*overtaken;
  }
  return line;
}

void LineLink::Discard() {
  buffer_.clear();
  discarding_line_ = false;
  if (fd_ < 0) return;
  char chunk[512];
  for (int i = 0; i < 64; ++i) {  // bounded: a device that floods cannot hold the caller
    const ssize_t n = ::read(fd_, chunk, sizeof chunk);
    if (n > 0) continue;
    if (n == 0) Close();
    return;
  }
}

std::optional<std::string> LineLink::Query(const std::string& line, double timeout_s, std::string* why) {
  const auto deadline = Deadline(timeout_s);
  Discard();
  if (std::string failure = WriteLine(line, timeout_s); !failure.empty()) {
    *why = std::move(failure);
    return std::nullopt;
  }
  return ReadLineBy(deadline, timeout_s, why);  // a timeout says the caller's, not what was left
}

std::string ParseNumberReply(const std::string& reply, double* out) {
  const char* begin = reply.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  while (end != nullptr && (*end == ' ' || *end == '\t')) ++end;
  if (end == begin || end == nullptr || *end != '\0' || errno == ERANGE || !std::isfinite(value)) {
    return fmt::format("\"{}\" is not a number", reply.substr(0, 40));
  }
  *out = value;
  return {};
}

std::string ParseStokesReply(const std::string& reply, int vectors, double min_dop, StokesVector* out) {
  std::vector<double> values;
  size_t start = 0;
  while (start <= reply.size()) {
    const size_t comma = reply.find(',', start);
    std::string field = reply.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const size_t first = field.find_first_not_of(" \t");
    field = first == std::string::npos ? std::string() : field.substr(first);
    double value = 0.0;
    if (const std::string why = ParseNumberReply(field, &value); !why.empty()) {
      return fmt::format("field {} of \"{}\": {}", values.size() + 1, reply.substr(0, 60), why);
    }
    values.push_back(value);
    if (comma == std::string::npos || values.size() > 16) break;
    start = comma + 1;
  }
  if (static_cast<int>(values.size()) != 3 * vectors) {
    return fmt::format("{} numbers in \"{}\"; expected {}", values.size(), reply.substr(0, 60), 3 * vectors);
  }
  for (int v = 0; v < vectors; ++v) {
    const StokesVector s(values[3 * v], values[3 * v + 1], values[3 * v + 2]);
    const double dop = s.norm();
    if (!(dop >= min_dop) || dop > 1.05) {
      return fmt::format("|S| = {:.4g} (degree of polarization) outside [{:g}, 1.05]", dop, min_dop);
    }
    out[v] = s / dop;
  }
  return {};
}

void ExchangeTimes::Add(double us) {
  if (window_.size() < kCapacity) {
    window_.push_back(us);
  } else {
    window_[next_] = us;
  }
  next_ = (next_ + 1) % kCapacity;
  ++count_;
}

double ExchangeTimes::Percentile(double q) const {
  if (window_.empty()) return NAN;
  std::vector<double> sorted = window_;
  const size_t rank = std::min(sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size())));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
  return sorted[rank];
}

DacPoint Quantize(double volts, double volts_min, double volts_max, int bits) {
  const double clamped = std::clamp(volts, volts_min, volts_max);
  if (bits <= 0) return {0, clamped};
  const double steps = std::ldexp(1.0, bits) - 1.0;
  const double lsb = (volts_max - volts_min) / steps;
  const double code = std::round((clamped - volts_min) / lsb);
  return {static_cast<int64_t>(code), volts_min + code * lsb};
}

}  // namespace dpc::instrument
