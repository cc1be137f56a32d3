#pragma once
// dpc-emulator's ends towards the operating system: TCP sockets listening on 127.0.0.1 only,
// accepted connections, pseudo-terminals a client opens as serial ports, and the wake-up of the
// poll loop. Every descriptor is non-blocking and close-on-exec. The loop that drives the
// EmulatorCore with them is the service's (main.cc).

#include <string>
#include <string_view>
#include <utility>

namespace dpc::services {

/// Owns a file descriptor (-1: none) and closes it.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() { reset(); }
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset();

 private:
  int fd_ = -1;
};

/// A TCP socket listening on 127.0.0.1:`port` (0: a free port the kernel picks). Throws
/// std::runtime_error naming `what` (the option that chose the port) when it cannot.
FileDescriptor ListenOnLoopback(int port, const std::string& what);
/// The local port `socket` is bound to.
int BoundPort(int socket);
/// A connection waiting on `listener`, or an invalid descriptor when none is (or accept failed:
/// `*error` is then errno, else 0).
FileDescriptor AcceptConnection(int listener, int* error);

/// What a non-blocking read or write did.
struct IoResult {
  enum class Kind { kDone, kWouldBlock, kClosed } kind = Kind::kDone;
  size_t bytes = 0;
};
/// Reads up to `capacity` bytes; kClosed at end of file or on an error other than EAGAIN/EINTR.
IoResult ReadSome(int fd, char* buffer, size_t capacity);
/// Writes what it can of `data` (send without SIGPIPE on a socket, write on a terminal).
IoResult WriteSome(int fd, std::string_view data, bool socket);

/// A pseudo-terminal (posix_openpt, grantpt, unlockpt) in raw mode: a client opens its slave,
/// path(), as a serial port; the emulator reads and writes the master. The emulator holds the
/// slave open too, so that the master does not hang up (poll would report POLLHUP at once,
/// forever) while no client has it open. Throws std::runtime_error when it cannot be made.
class PseudoTerminal {
 public:
  PseudoTerminal();
  int master() const { return master_.get(); }
  const std::string& path() const { return path_; }
  /// Drops what waits in either direction: replies no client read, a client's unsent bytes.
  void Flush();

 private:
  FileDescriptor master_;
  FileDescriptor slave_;
  std::string path_;
};

/// An eventfd another thread signals (stop()) to wake the poll loop at once.
class Wakeup {
 public:
  Wakeup();  ///< throws std::runtime_error
  int fd() const { return fd_.get(); }
  /// Async-signal- and thread-safe.
  void Signal();
  /// Consumes the pending wake-ups.
  void Drain();

 private:
  FileDescriptor fd_;
};

}  // namespace dpc::services
