#include "emulator_io.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace dpc::services {
namespace {

std::runtime_error SystemError(const std::string& what) {
  return std::runtime_error(fmt::format("{}: {}", what, std::strerror(errno)));
}

bool TransientError(int error) { return error == EAGAIN || error == EWOULDBLOCK || error == EINTR; }

}  // namespace

void FileDescriptor::reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

FileDescriptor ListenOnLoopback(int port, const std::string& what) {
  FileDescriptor socket(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!socket.valid()) throw SystemError(what + ": socket");
  // A restarted emulator takes its fixed port back at once (connections of the previous one
  // may linger in TIME_WAIT).
  const int yes = 1;
  ::setsockopt(socket.get(), SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<uint16_t>(port));
  if (::bind(socket.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    throw SystemError(fmt::format("{} {}: bind 127.0.0.1:{}", what, port, port));
  }
  if (::listen(socket.get(), 64) != 0) throw SystemError(fmt::format("{} {}: listen", what, port));
  return socket;
}

int BoundPort(int socket) {
  sockaddr_in address{};
  socklen_t length = sizeof address;
  if (::getsockname(socket, reinterpret_cast<sockaddr*>(&address), &length) != 0) throw SystemError("getsockname");
  return ntohs(address.sin_port);
}

FileDescriptor AcceptConnection(int listener, int* error) {
  *error = 0;
  FileDescriptor connection(::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
  if (!connection.valid()) {
    if (!TransientError(errno)) *error = errno;
    return connection;
  }
  // Replies are short lines a client waits for: no Nagle delay.
  const int yes = 1;
  ::setsockopt(connection.get(), IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
  return connection;
}

IoResult ReadSome(int fd, char* buffer, size_t capacity) {
  const ssize_t n = ::read(fd, buffer, capacity);
  if (n > 0) return {IoResult::Kind::kDone, static_cast<size_t>(n)};
  if (n < 0 && TransientError(errno)) return {IoResult::Kind::kWouldBlock, 0};
  return {IoResult::Kind::kClosed, 0};
}

IoResult WriteSome(int fd, std::string_view data, bool socket) {
  const ssize_t n = socket ? ::send(fd, data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT)
                           : ::write(fd, data.data(), data.size());
  if (n >= 0) return {IoResult::Kind::kDone, static_cast<size_t>(n)};
  if (TransientError(errno)) return {IoResult::Kind::kWouldBlock, 0};
  return {IoResult::Kind::kClosed, 0};
}

PseudoTerminal::PseudoTerminal() {
  master_ = FileDescriptor(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!master_.valid()) throw SystemError("--pty: posix_openpt");
  if (::grantpt(master_.get()) != 0) throw SystemError("--pty: grantpt");
  if (::unlockpt(master_.get()) != 0) throw SystemError("--pty: unlockpt");
  char name[128];
  if (::ptsname_r(master_.get(), name, sizeof name) != 0) throw SystemError("--pty: ptsname_r");
  path_ = name;
  if (::fcntl(master_.get(), F_SETFL, ::fcntl(master_.get(), F_GETFL) | O_NONBLOCK) != 0) {
    throw SystemError("--pty: fcntl O_NONBLOCK");
  }
  slave_ = FileDescriptor(::open(path_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK));
  if (!slave_.valid()) throw SystemError("--pty: open " + path_);
  // Raw: bytes pass as they are (no echo, no line editing, no CR/LF translation), as on a
  // serial line to an instrument.
  termios mode{};
  if (::tcgetattr(slave_.get(), &mode) != 0) throw SystemError("--pty: tcgetattr " + path_);
  ::cfmakeraw(&mode);
  mode.c_cc[VMIN] = 1;
  mode.c_cc[VTIME] = 0;
  if (::tcsetattr(slave_.get(), TCSANOW, &mode) != 0) throw SystemError("--pty: tcsetattr " + path_);
}

void PseudoTerminal::Flush() { ::tcflush(slave_.get(), TCIOFLUSH); }

Wakeup::Wakeup() : fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (!fd_.valid()) throw SystemError("eventfd");
}

void Wakeup::Signal() {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(fd_.get(), &one, sizeof one);
}

void Wakeup::Drain() {
  uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = ::read(fd_.get(), &count, sizeof count);
}

}  // namespace dpc::services
