#include "dashboard_server.h"

#include <fmt/format.h>

// Boost 1.74's Asio uses std::exchange without including <utility> (C++20 builds).
#include <utility>

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

namespace dpc::tools {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

constexpr size_t kMaxHeaderBytes = 8192;
constexpr size_t kMaxClientMessageBytes = 4096;
constexpr auto kRequestTimeout = std::chrono::seconds(10);

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The host name of a Host header ("127.0.0.1:8080" → "127.0.0.1", "[::1]:80" → "::1").
std::string HostName(std::string host) {
  if (!host.empty() && host.front() == '[') {
    const size_t end = host.find(']');
    return end == std::string::npos ? std::string() : host.substr(1, end - 1);
  }
  const size_t colon = host.rfind(':');
  if (colon != std::string::npos) host.resize(colon);
  return host;
}

/// A Host the dashboard answers: an address literal or localhost. A name that resolves here only
/// because some site's DNS says so (DNS rebinding) is refused, so a page of another site cannot
/// read the dashboard or steer the bench through the user's browser.
bool AcceptableHost(const std::string& host_header) {
  const std::string name = HostName(host_header);
  if (name == "localhost") return true;
  boost::system::error_code ec;
  net::ip::make_address(name, ec);
  return !ec;
}

}  // namespace

std::string DashboardContentType(const std::string& path) {
  static const std::pair<const char*, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".svg", "image/svg+xml"},
      {".png", "image/png"},
      {".ico", "image/x-icon"},
  };
  for (const auto& [extension, type] : kTypes) {
    if (EndsWith(path, extension)) return type;
  }
  return "";
}

std::string DashboardAssetPath(const std::string& assets_dir, const std::string& target) {
  if (target.empty() || target.front() != '/' || target.size() > 256) return "";
  std::string path = target == "/" ? "/index.html" : target;
  for (char c : path) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '/' ||
                       c == '.' || c == '_' || c == '-';
    if (!plain) return "";  // queries, escapes, anything unusual
  }
  if (path.find("/.") != std::string::npos || path.find("//") != std::string::npos) return "";  // .., dot-files
  if (DashboardContentType(path).empty()) return "";
  return assets_dir + path;
}

// ---- sessions

class WebSocketSession;

struct DashboardServer::Impl {
  DashboardServerOptions options;
  MessageHandler on_message;
  // Before io: the sessions that io's pending handlers still own reach these as they go.
  mutable std::mutex mutex;  ///< guards clients and next_id
  std::map<uint64_t, std::weak_ptr<WebSocketSession>> clients;
  uint64_t next_id = 1;
  std::atomic<size_t> connections{0};
  std::atomic<size_t> open_clients{0};  ///< WebSocket sessions past their handshake
  net::io_context io{1};
  tcp::acceptor acceptor{io};
  std::thread thread;
  int port = 0;

  void Accept();
};

class WebSocketSession : public std::enable_shared_from_this<WebSocketSession> {
 public:
  WebSocketSession(tcp::socket&& socket, DashboardServer::Impl* server, uint64_t id)
      : ws_(std::move(socket)), server_(server), id_(id) {}

  ~WebSocketSession() {
    if (open_) --server_->open_clients;
    std::lock_guard<std::mutex> lock(server_->mutex);
    server_->clients.erase(id_);
  }

  void Start(http::request<http::empty_body> request) {
    beast::get_lowest_layer(ws_).expires_never();
    // Handshake within 30 s; a page that answers no ping for 5 min is gone (a browser answers
    // pings by itself, so an open page stays connected however long it only listens).
    auto timeout = websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeout.keep_alive_pings = true;
    ws_.set_option(timeout);
    ws_.read_message_max(kMaxClientMessageBytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->open_ = true;
      ++self->server_->open_clients;
      self->Read();
    });
  }

  /// From any thread: queue `text`; `droppable` text (snapshots) is dropped when the queue is
  /// full, so a slow page never makes the server grow.
  void Deliver(std::shared_ptr<const std::string> text, bool droppable) {
    net::post(ws_.get_executor(), [self = shared_from_this(), text = std::move(text), droppable] {
      if (!self->open_) return;  // the handshake is not done: nothing may be written yet
      if (droppable && self->queue_.size() >= self->server_->options.max_queued_messages) return;
      if (self->queue_.size() >= 4 * self->server_->options.max_queued_messages) return;
      self->queue_.push_back(text);
      if (self->queue_.size() == 1) self->Write();
    });
  }

 private:
  void Read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) return;  // closed, too large, timed out: the session ends
      if (self->ws_.got_text()) {
        const std::string text = beast::buffers_to_string(self->buffer_.data());
        if (self->server_->on_message) self->server_->on_message(self->id_, text);
      }
      self->buffer_.consume(self->buffer_.size());
      self->Read();
    });
  }

  void Write() {
    ws_.text(true);
    ws_.async_write(net::buffer(*queue_.front()), [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) return;
      self->queue_.pop_front();
      if (!self->queue_.empty()) self->Write();
    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  DashboardServer::Impl* server_;
  uint64_t id_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  bool open_ = false;  ///< the handshake completed (on the session's strand)
};

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, DashboardServer::Impl* server) : stream_(std::move(socket)), server_(server) {
    ++server_->connections;
  }
  ~HttpSession() { --server_->connections; }

  void Read() {
    parser_.emplace();
    parser_->header_limit(kMaxHeaderBytes);
    stream_.expires_after(kRequestTimeout);
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) {
        if (ec != http::error::end_of_stream) self->stream_.socket().close(ec);
        return;
      }
      self->Handle(self->parser_->release());
    });
  }

 private:
  template <class Body>
  void Send(http::response<Body>&& response) {
    auto message = std::make_shared<http::response<Body>>(std::move(response));
    http::async_write(stream_, *message, [self = shared_from_this(), message](beast::error_code ec, size_t) {
      if (ec || message->need_eof()) {
        beast::error_code ignored;
        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
        return;
      }
      self->Read();
    });
  }

  void SendText(http::status status, const http::request<http::empty_body>& request, const std::string& text) {
    http::response<http::string_body> response{status, request.version()};
    response.set(http::field::content_type, "text/plain; charset=utf-8");
    response.set(http::field::cache_control, "no-store");
    response.keep_alive(request.keep_alive());
    response.body() = text + "\n";
    response.prepare_payload();
    Send(std::move(response));
  }

  void Handle(http::request<http::empty_body> request) {
    const std::string target(request.target());
    if (!AcceptableHost(std::string(request[http::field::host]))) {
      SendText(http::status::misdirected_request, request,
               "dpc dashboard: open it by address (http://127.0.0.1:PORT/) or as localhost");
      return;
    }
    if (websocket::is_upgrade(request)) {
      if (target != "/ws") return SendText(http::status::not_found, request, "no WebSocket here: use /ws");
      const std::string origin(request[http::field::origin]);
      const std::string own = "http://" + std::string(request[http::field::host]);
      if (!origin.empty() && origin != own) {
        return SendText(http::status::forbidden, request,
                        fmt::format("dpc dashboard: WebSocket from another origin ({}) refused", origin.substr(0, 100)));
      }
      std::shared_ptr<WebSocketSession> session;
      {
        std::lock_guard<std::mutex> lock(server_->mutex);
        if (server_->clients.size() < server_->options.max_clients) {
          const uint64_t id = server_->next_id++;
          session = std::make_shared<WebSocketSession>(stream_.release_socket(), server_, id);
          server_->clients[id] = session;
        }
      }
      if (!session) {
        return SendText(http::status::service_unavailable, request,
                        fmt::format("dpc dashboard: {} pages are connected already", server_->options.max_clients));
      }
      session->Start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      return SendText(http::status::method_not_allowed, request, "dpc dashboard: only GET and HEAD");
    }
    const std::string path = DashboardAssetPath(server_->options.assets_dir, target);
    if (path.empty()) return SendText(http::status::not_found, request, "not found");
    http::file_body::value_type body;
    beast::error_code ec;
    body.open(path.c_str(), beast::file_mode::scan, ec);
    if (ec) return SendText(http::status::not_found, request, "not found");
    const auto size = body.size();
    http::response<http::file_body> response{std::piecewise_construct, std::make_tuple(std::move(body)),
                                             std::make_tuple(http::status::ok, request.version())};
    response.set(http::field::content_type, DashboardContentType(path));
    response.set(http::field::cache_control, "no-cache");
    response.set("X-Content-Type-Options", "nosniff");
    response.set("Content-Security-Policy",
                 "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
                 "connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'");
    response.content_length(size);
    response.keep_alive(request.keep_alive());
    if (request.method() == http::verb::head) {
      http::response<http::empty_body> head{http::status::ok, request.version()};
      head.base() = response.base();
      head.content_length(size);
      head.keep_alive(request.keep_alive());
      return Send(std::move(head));
    }
    Send(std::move(response));
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  DashboardServer::Impl* server_;
};

void DashboardServer::Impl::Accept() {
  acceptor.async_accept(net::make_strand(io), [this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted) return;  // stopping
    if (!ec) {
      if (connections.load() >= options.max_connections) {
        socket.close(ec);  // over the limit: closed at once
      } else {
        std::make_shared<HttpSession>(std::move(socket), this)->Read();
      }
    }
    Accept();
  });
}

// ---- the server

DashboardServer::DashboardServer(DashboardServerOptions options, MessageHandler on_message)
    : impl_(std::make_shared<Impl>()) {
  impl_->options = std::move(options);
  impl_->on_message = std::move(on_message);
  const std::string index = impl_->options.assets_dir + "/index.html";
  if (!std::filesystem::is_regular_file(index)) {
    throw std::runtime_error(fmt::format("the dashboard's page is missing: {} (give --assets DIR)", index));
  }
  boost::system::error_code ec;
  const net::ip::address address = net::ip::make_address(impl_->options.bind_address, ec);
  if (ec) throw std::runtime_error(fmt::format("--bind {}: not an IP address", impl_->options.bind_address));
  const tcp::endpoint endpoint(address, static_cast<unsigned short>(impl_->options.port));
  impl_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl_->acceptor.bind(endpoint, ec);
  if (!ec) impl_->acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error(
        fmt::format("cannot listen on {}:{}: {}", impl_->options.bind_address, impl_->options.port, ec.message()));
  }
  impl_->port = impl_->acceptor.local_endpoint().port();
  impl_->Accept();
  impl_->thread = std::thread([impl = impl_] { impl->io.run(); });
}

DashboardServer::~DashboardServer() {
  net::post(impl_->io, [impl = impl_.get()] {
    boost::system::error_code ignored;
    impl->acceptor.close(ignored);
  });
  impl_->io.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

int DashboardServer::port() const { return impl_->port; }

void DashboardServer::Broadcast(const std::string& text) {
  auto shared = std::make_shared<const std::string>(text);
  std::vector<std::shared_ptr<WebSocketSession>> sessions;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (auto& [id, weak] : impl_->clients) {
      if (auto session = weak.lock()) sessions.push_back(std::move(session));
    }
  }
  // Outside the lock: the last owner of a closed session may be this vector, and its
  // destructor takes the lock.
  for (auto& session : sessions) session->Deliver(shared, true);
}

void DashboardServer::Send(uint64_t client_id, const std::string& text) {
  std::shared_ptr<WebSocketSession> session;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    auto it = impl_->clients.find(client_id);
    if (it != impl_->clients.end()) session = it->second.lock();
  }
  if (session) session->Deliver(std::make_shared<const std::string>(text), false);
}

size_t DashboardServer::clients() const { return impl_->open_clients.load(); }

}  // namespace dpc::tools
