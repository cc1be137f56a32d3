#pragma once
// A scripted line-protocol instrument on 127.0.0.1 for unit tests: a thread that accepts one
// connection at a time on an ephemeral port and answers each line it reads with what the
// test's handler returns (nullopt: no answer). The test can hang up the connection.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <thread>

namespace dpc::testing {

class LineServer {
 public:
  using Handler = std::function<std::optional<std::string>(const std::string& line)>;

  explicit LineServer(Handler handler) : handler_(std::move(handler)) {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address);
    ::listen(listener_, 4);
    socklen_t length = sizeof address;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this] { Serve(); });
  }
  ~LineServer() {
    stop_ = true;
    thread_.join();
    ::close(listener_);
  }
  LineServer(const LineServer&) = delete;
  LineServer& operator=(const LineServer&) = delete;

  int port() const { return port_; }
  /// Closes the current connection; the next one is accepted.
  void HangUp() { hang_up_ = true; }
  int connections() const { return connections_; }

 private:
  void Serve() {
    int peer = -1;
    std::string buffer;
    while (!stop_) {
      if (peer < 0) {
        pollfd p{listener_, POLLIN, 0};
        if (::poll(&p, 1, 10) > 0) {
          peer = ::accept(listener_, nullptr, nullptr);
          ++connections_;
          buffer.clear();
        }
        continue;
      }
      if (hang_up_.exchange(false)) {
        ::close(peer);
        peer = -1;
        continue;
      }
      pollfd p{peer, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      char chunk[256];
      const ssize_t n = ::read(peer, chunk, sizeof chunk);
      if (n <= 0) {
        ::close(peer);
        peer = -1;
        continue;
      }
      buffer.append(chunk, static_cast<size_t>(n));
      for (size_t end; (end = buffer.find('\n')) != std::string::npos;) {
        const std::string line = buffer.substr(0, end);
        buffer.erase(0, end + 1);
        if (const std::optional<std::string> reply = handler_(line)) {
          ::send(peer, reply->data(), reply->size(), MSG_NOSIGNAL);
        }
      }
    }
    if (peer >= 0) ::close(peer);
  }

  Handler handler_;
  int listener_ = -1, port_ = 0;
  std::atomic<bool> stop_{false}, hang_up_{false};
  std::atomic<int> connections_{0};
  std::thread thread_;
};

}  // namespace dpc::testing
