// The dashboard's web server against a client on loopback: it serves the page's files and
// nothing else, refuses other sites (Origin, DNS-rebinding Host), bounds what a page may send
// and how many pages connect, and pushes text to every page.
#include "dashboard_server.h"

#include <gtest/gtest.h>

#include <utility>  // before Boost 1.74's Asio (std::exchange)

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <sys/socket.h>
#include <unistd.h>

namespace dpc::tools {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

TEST(DashboardAssetPathTest, OnlyPlainPathsToKnownFileTypesInsideTheDirectory) {
  EXPECT_EQ(DashboardAssetPath("/a", "/"), "/a/index.html");
  EXPECT_EQ(DashboardAssetPath("/a", "/dashboard.js"), "/a/dashboard.js");
  EXPECT_EQ(DashboardAssetPath("/a", "/vendor/three/three.module.js"), "/a/vendor/three/three.module.js");
  for (const char* refused : {"", "index.html", "/../etc/passwd", "/vendor/../../x.js", "/%2e%2e/x.js", "/.env",
                              "/a/.git/config.json", "/index.html?x=1", "/x.sh", "/bin/dpc", "//etc/x.js",
                              "/a b.js"}) {
    EXPECT_EQ(DashboardAssetPath("/a", refused), "") << refused;
  }
  EXPECT_EQ(DashboardAssetPath("/a", "/" + std::string(300, 'x') + ".js"), "");
  EXPECT_EQ(DashboardContentType("/a/x.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(DashboardContentType("/a/x.exe"), "");
}

class DashboardServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    assets_ = std::filesystem::temp_directory_path() / ("dpc-dashboard-test-" + std::to_string(getpid()));
    std::filesystem::create_directories(assets_ / "vendor");
    std::ofstream(assets_ / "index.html") << "<!DOCTYPE html><title>dpc</title>";
    std::ofstream(assets_ / "vendor" / "lib.js") << "export default 1;";
    std::ofstream(assets_.parent_path() / "secret.js") << "secret";
  }
  void TearDown() override {
    server_.reset();
    std::filesystem::remove_all(assets_);
  }
  void Start(size_t max_clients = 16) {
    DashboardServerOptions options;
    options.port = 0;
    options.assets_dir = assets_.string();
    options.max_clients = max_clients;
    server_ = std::make_unique<DashboardServer>(options, [this](uint64_t client, const std::string& text) {
      std::lock_guard<std::mutex> lock(mutex_);
      received_.emplace_back(client, text);
    });
  }

  /// One HTTP request; the response (status, body, content type).
  http::response<http::string_body> Get(const std::string& target, const std::string& host = "",
                                        http::verb verb = http::verb::get) {
    net::io_context io;
    beast::tcp_stream stream(io);
    stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(server_->port())));
    http::request<http::string_body> request{verb, target, 11};
    request.set(http::field::host, host.empty() ? "127.0.0.1:" + std::to_string(server_->port()) : host);
    request.prepare_payload();
    http::write(stream, request);
    beast::flat_buffer buffer;
    http::response_parser<http::string_body> parser;
    parser.skip(verb == http::verb::head);  // a HEAD response announces a body it does not send
    http::read(stream, buffer, parser);
    return parser.release();
  }

  /// A WebSocket handshake with `origin`; the stream if it was accepted.
  std::unique_ptr<websocket::stream<tcp::socket>> Connect(net::io_context& io, const std::string& origin,
                                                          beast::error_code* ec) {
    auto ws = std::make_unique<websocket::stream<tcp::socket>>(io);
    ws->next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(server_->port())));
    ws->set_option(websocket::stream_base::decorator([origin](websocket::request_type& r) {
      if (!origin.empty()) r.set(http::field::origin, origin);
    }));
    ws->handshake("127.0.0.1:" + std::to_string(server_->port()), "/ws", *ec);
    return ws;
  }

  /// Reads one message, or fails after 10 s (the socket is shut down: the read returns an error
  /// instead of hanging the test).
  static std::string ReadWithin(websocket::stream<tcp::socket>& ws, beast::error_code* ec) {
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    std::thread watchdog([&] {
      std::unique_lock<std::mutex> lock(m);
      if (!cv.wait_for(lock, std::chrono::seconds(10), [&] { return done; })) {
        ::shutdown(ws.next_layer().native_handle(), SHUT_RDWR);
      }
    });
    beast::flat_buffer buffer;
    ws.read(buffer, *ec);
    {
      std::lock_guard<std::mutex> lock(m);
      done = true;
    }
    cv.notify_one();
    watchdog.join();
    return beast::buffers_to_string(buffer.data());
  }

  bool WaitFor(const std::function<bool()>& done) {
    for (int i = 0; i < 500; ++i) {
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return done();
  }

  std::filesystem::path assets_;
  std::unique_ptr<DashboardServer> server_;
  std::mutex mutex_;
  std::vector<std::pair<uint64_t, std::string>> received_;
};

TEST_F(DashboardServerTest, ServesThePageAndItsFilesAndNothingElse) {
  Start();
  auto index = Get("/");
  EXPECT_EQ(index.result(), http::status::ok);
  EXPECT_EQ(index.body(), "<!DOCTYPE html><title>dpc</title>");
  EXPECT_EQ(index[http::field::content_type], "text/html; charset=utf-8");
  EXPECT_NE(std::string(index["Content-Security-Policy"]).find("default-src 'self'"), std::string::npos);
  EXPECT_EQ(Get("/vendor/lib.js").body(), "export default 1;");
  EXPECT_EQ(Get("/../secret.js").result(), http::status::not_found);
  EXPECT_EQ(Get("/vendor/../../secret.js").result(), http::status::not_found);
  EXPECT_EQ(Get("/missing.js").result(), http::status::not_found);
  EXPECT_EQ(Get("/", "", http::verb::post).result(), http::status::method_not_allowed);
  auto head = Get("/", "", http::verb::head);
  EXPECT_EQ(head.result(), http::status::ok);
}

TEST_F(DashboardServerTest, AHostNameThatIsNotAnAddressOrLocalhostIsRefused) {
  Start();
  // DNS rebinding: a site whose name now resolves to 127.0.0.1 sends its own name as Host.
  EXPECT_EQ(Get("/", "attacker.example:8080").result(), http::status::misdirected_request);
  EXPECT_EQ(Get("/", "localhost:" + std::to_string(server_->port())).result(), http::status::ok);
  EXPECT_EQ(Get("/", "[::1]:8080").result(), http::status::ok);
}

TEST_F(DashboardServerTest, AWebSocketFromAnotherOriginIsRefusedOneFromThePageWorksBothWays) {
  Start();
  net::io_context io;
  beast::error_code ec;
  Connect(io, "http://attacker.example", &ec);
  EXPECT_TRUE(ec) << "a WebSocket from another site was accepted";

  auto ws = Connect(io, "http://127.0.0.1:" + std::to_string(server_->port()), &ec);
  ASSERT_FALSE(ec) << ec.message();
  ASSERT_TRUE(WaitFor([&] { return server_->clients() == 1; }));
  server_->Broadcast(R"({"type":"snapshot"})");
  EXPECT_EQ(ReadWithin(*ws, &ec), R"({"type":"snapshot"})");
  ASSERT_FALSE(ec) << ec.message();
  ws->write(net::buffer(std::string(R"({"type":"set_target"})")));
  ASSERT_TRUE(WaitFor([&] {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_.size() == 1;
  }));
  const uint64_t client = received_[0].first;
  EXPECT_EQ(received_[0].second, R"({"type":"set_target"})");
  server_->Send(client, "answer");
  EXPECT_EQ(ReadWithin(*ws, &ec), "answer");
  EXPECT_FALSE(ec) << ec.message();
}

TEST_F(DashboardServerTest, AnOversizedMessageEndsThatPageOnlyAndTheServerGoesOn) {
  Start();
  net::io_context io;
  beast::error_code ec;
  auto ws = Connect(io, "", &ec);
  ASSERT_FALSE(ec) << ec.message();
  ws->write(net::buffer(std::string(64 * 1024, 'x')), ec);
  ReadWithin(*ws, &ec);
  EXPECT_TRUE(ec) << "the connection stayed open after a 64-KiB message";
  EXPECT_TRUE(WaitFor([&] { return server_->clients() == 0; }));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_TRUE(received_.empty());
  }
  EXPECT_EQ(Get("/").result(), http::status::ok);
  auto again = Connect(io, "", &ec);
  EXPECT_FALSE(ec) << ec.message();
}

TEST_F(DashboardServerTest, PagesBeyondTheLimitAreRefused) {
  Start(/*max_clients=*/2);
  net::io_context io;
  beast::error_code ec;
  auto a = Connect(io, "", &ec);
  ASSERT_FALSE(ec);
  auto b = Connect(io, "", &ec);
  ASSERT_FALSE(ec);
  auto c = Connect(io, "", &ec);
  EXPECT_TRUE(ec) << "a third page was accepted with a limit of 2";
  EXPECT_EQ(server_->clients(), 2u);
}

TEST_F(DashboardServerTest, AMissingPageOrABusyPortIsAClearError) {
  DashboardServerOptions options;
  options.port = 0;
  options.assets_dir = (assets_ / "nowhere").string();
  try {
    DashboardServer server(options, nullptr);
    FAIL() << "started without its page";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere/index.html"), std::string::npos) << e.what();
  }
  Start();
  options.assets_dir = assets_.string();
  options.port = server_->port();
  try {
    DashboardServer second(options, nullptr);
    FAIL() << "two servers on one port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(options.port)),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace dpc::tools
