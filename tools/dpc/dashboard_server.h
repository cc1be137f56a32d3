#pragma once
// The web server of `dpc dashboard` (Boost.Beast, one I/O thread): static files from the assets
// directory over HTTP, and a WebSocket at /ws on which the server pushes JSON text and receives
// the page's requests.
//
// A browser is a peer like any other: requests are size- and time-limited (8 KiB headers, no
// bodies, 10 s to send a request), only GET/HEAD of files inside the assets directory are
// served, WebSocket messages from the page are at most 4 KiB, a WebSocket upgrade whose Origin is
// not this server's own is refused (another site open in the same browser cannot steer the
// bench), at most `max_clients` pages are connected, and a page that reads too slowly loses
// snapshots instead of growing a queue.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace dpc::tools {

struct DashboardServerOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;                 ///< 0: any free port (see DashboardServer::port())
  std::string assets_dir;          ///< index.html and what it loads
  size_t max_clients = 16;         ///< WebSocket connections at once
  size_t max_connections = 64;     ///< HTTP connections at once
  size_t max_queued_messages = 8;  ///< per WebSocket client; beyond, broadcasts are dropped
};

class DashboardServer {
 public:
  /// Called on the server's thread with each text message a page sends, and the client's id
  /// for Send().
  using MessageHandler = std::function<void(uint64_t client_id, const std::string& text)>;

  /// Binds and starts serving. Throws std::runtime_error naming the address on failure
  /// (address in use, not an address of this host, the assets directory missing).
  DashboardServer(DashboardServerOptions options, MessageHandler on_message);
  ~DashboardServer();  ///< closes every connection and joins the thread
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  int port() const;
  /// Sends `text` to every connected page (thread-safe).
  void Broadcast(const std::string& text);
  /// Sends `text` to one page, if still connected (thread-safe).
  void Send(uint64_t client_id, const std::string& text);
  /// WebSocket clients connected now (their handshake done: a Broadcast reaches them).
  size_t clients() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

/// The content type served for a file name's extension ("" for one not served).
std::string DashboardContentType(const std::string& path);

/// The file under `assets_dir` that the request target names ("/" → index.html), or "" when the
/// target is not one the server serves (not a plain path, "..", a query, a dot-file, an unknown
/// extension). Pure: does not touch the file system.
std::string DashboardAssetPath(const std::string& assets_dir, const std::string& target);

}  // namespace dpc::tools
