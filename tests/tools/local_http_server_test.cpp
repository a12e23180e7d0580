// The server of `umbra view --serve` (tools/local_http_server.cpp) with
// clients of the test's own on real sockets: the page goes only to requests
// whose Host is 127.0.0.1, localhost or [::1] (a DNS-rebinding page's own
// name is refused); a client that sends part of a request and stalls, and
// idle connections, delay no other request (the other request is answered
// while the stalled connection is still open, then the stalled one finishes
// and is answered too: one client at a time would wait forever here); a
// request that drips a byte at a time is cut at its deadline however often
// its bytes come; connections beyond the limit get 503 at once; request
// lines reach the log with unprintable bytes as \xNN. No test measures
// time: the waits that the old design would make endless are bounded by
// ctest's TIMEOUT (tests/tools/CMakeLists.txt).
#include "local_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace umbra::cli {
namespace {

using namespace std::chrono_literals;

const std::string kPage = "<!doctype html><title>map</title><p>the map's page</p>\n";

/// A server answering on its own thread from construction to destruction,
/// logging to a temporary file.
class RunningServer {
 public:
  explicit RunningServer(ServerLimits limits = {}) : server_(kPage, 0, limits), log_(std::tmpfile()) {
    thread_ = std::thread([this] { server_.serve(log_, stop_); });
  }
  ~RunningServer() {
    stop();
    std::fclose(log_);
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  [[nodiscard]] int port() const { return server_.port(); }
  /// Everything logged so far.
  std::string log() {
    std::fflush(log_);
    std::string text;
    std::rewind(log_);
    for (int c = std::fgetc(log_); c != EOF; c = std::fgetc(log_)) text += static_cast<char>(c);
    return text;
  }

 private:
  LocalHttpServer server_;
  std::FILE* log_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// A blocking client connection to 127.0.0.1:port.
class Client {
 public:
  explicit Client(int port) : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
    EXPECT_TRUE(connected_) << "cannot connect to port " << port;
  }
  ~Client() { ::close(fd_); }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  bool send(const std::string& bytes) {
    std::size_t sent = 0;
    while (sent < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) return false;
      sent += static_cast<std::size_t>(n);
    }
    return true;
  }
  /// Everything until the server closes the connection.
  std::string receive_all() {
    std::string bytes;
    char buffer[4096];
    for (ssize_t n; (n = ::recv(fd_, buffer, sizeof buffer, 0)) > 0;) bytes.append(buffer, static_cast<std::size_t>(n));
    return bytes;
  }
  /// Whether the server answered or closed: something to read (or its end)
  /// after waiting at most `wait`.
  bool answered_within(std::chrono::milliseconds wait) {
    pollfd ready{fd_, POLLIN, 0};
    return ::poll(&ready, 1, static_cast<int>(wait.count())) > 0;
  }

 private:
  int fd_;
  bool connected_ = false;
};

std::string request(const std::string& target, const std::string& host, const std::string& method = "GET") {
  return method + " " + target + " HTTP/1.1\r\nHost: " + host + "\r\nUser-Agent: umbra-test\r\n\r\n";
}

/// The response to one request on a connection of its own.
std::string exchange(int port, const std::string& bytes) {
  Client client(port);
  EXPECT_TRUE(client.send(bytes));
  return client.receive_all();
}

int status_of(const std::string& response) {
  if (response.rfind("HTTP/1.1 ", 0) != 0 || response.size() < 12) return 0;
  return std::stoi(response.substr(9, 3));
}

std::string body_of(const std::string& response) {
  const std::size_t end = response.find("\r\n\r\n");
  return end == std::string::npos ? "" : response.substr(end + 4);
}

/// Long enough never to pass during a test: these tests are about waiting
/// for others, not about the deadlines.
ServerLimits patient() {
  ServerLimits limits;
  limits.head_deadline = 10min;
  limits.send_deadline = 10min;
  return limits;
}

TEST(LocalHttpServer, ServesThePageToRequestsForTheLoopbackAddress) {
  RunningServer server(patient());
  const std::string port = std::to_string(server.port());
  for (const std::string& host : std::vector<std::string>{"127.0.0.1:" + port, "localhost:" + port, "LocalHost:" + port,
                                                          "[::1]:" + port, "127.0.0.1", "localhost"}) {
    const std::string response = exchange(server.port(), request("/", host));
    EXPECT_EQ(status_of(response), 200) << host << ": " << response;
    EXPECT_EQ(body_of(response), kPage) << host;
  }
  EXPECT_EQ(body_of(exchange(server.port(), request("/index.html", "localhost"))), kPage);
  const std::string head = exchange(server.port(), request("/", "localhost", "HEAD"));
  EXPECT_EQ(status_of(head), 200);
  EXPECT_EQ(body_of(head), "");
  EXPECT_NE(head.find("Content-Length: " + std::to_string(kPage.size()) + "\r\n"), std::string::npos) << head;
  EXPECT_EQ(status_of(exchange(server.port(), request("/../etc/passwd", "localhost"))), 404);
  EXPECT_EQ(status_of(exchange(server.port(), request("/", "localhost", "POST"))), 405);
}

TEST(LocalHttpServer, RefusesRequestsForOtherHostsAsDnsRebindingSendsThem) {
  RunningServer server(patient());
  const std::string port = std::to_string(server.port());
  for (const std::string& host : std::vector<std::string>{
           "evil.example", "evil.example:" + port, "127.0.0.1.evil.example:" + port, "localhost.evil.example",
           "127.0.0.2:" + port, "localhost:" + port + "x", "localhost:", "127.0.0.1:123456", "[::2]:" + port, "::1",
           ""}) {
    const std::string response = exchange(server.port(), request("/", host));
    EXPECT_EQ(status_of(response), 403) << "Host: " << host << "\n" << response;
    EXPECT_EQ(response.find(kPage), std::string::npos) << host;
  }
  // No Host, or two (the second would be the one some other server reads).
  const std::string none = exchange(server.port(), "GET / HTTP/1.0\r\n\r\n");
  EXPECT_EQ(status_of(none), 400) << none;
  const std::string two = exchange(server.port(), "GET / HTTP/1.1\r\nHost: localhost\r\nhost: evil.example\r\n\r\n");
  EXPECT_EQ(status_of(two), 400) << two;
  EXPECT_EQ(two.find(kPage), std::string::npos);
  EXPECT_NE(server.log().find("GET / HTTP/1.1 (Host evil.example refused: 403)"), std::string::npos) << server.log();
}

TEST(LocalHttpServer, AStalledClientDoesNotDelayAnotherRequest) {
  RunningServer server(patient());
  Client stalled(server.port());
  ASSERT_TRUE(stalled.send("GET / HTTP/1.1\r\nHo"));  // half a request, then nothing
  // Served while `stalled` waits in the middle of its request (one client at
  // a time would wait for it until its deadline, ten minutes here).
  const std::string response = exchange(server.port(), request("/", "localhost"));
  EXPECT_EQ(status_of(response), 200) << response;
  EXPECT_EQ(body_of(response), kPage);
  // The stalled connection was open all along: it finishes and is answered.
  ASSERT_TRUE(stalled.send("st: localhost\r\n\r\n"));
  EXPECT_EQ(body_of(stalled.receive_all()), kPage);
}

TEST(LocalHttpServer, IdleConnectionsDoNotDelayAnotherRequest) {
  RunningServer server(patient());
  std::vector<std::unique_ptr<Client>> idle;
  for (int i = 0; i < 18; ++i) idle.push_back(std::make_unique<Client>(server.port()));
  ASSERT_TRUE(idle.back()->send("G"));
  const std::string response = exchange(server.port(), request("/", "127.0.0.1"));
  EXPECT_EQ(status_of(response), 200) << response;
  EXPECT_EQ(body_of(response), kPage);
  for (const auto& client : idle) EXPECT_FALSE(client->answered_within(0ms));  // still open, nothing said
}

TEST(LocalHttpServer, ARequestDrippingByteByByteIsCutAtItsDeadline) {
  ServerLimits limits = patient();
  limits.head_deadline = 300ms;
  RunningServer server(limits);
  Client dripping(server.port());
  ASSERT_TRUE(dripping.send("GET / HTTP/1.1\r\nX-Slow: "));
  // A byte every 20 ms, far more often than any per-read timeout, until the
  // server answers; without a deadline for the whole head this never ends.
  std::size_t dripped = 0;
  while (!dripping.answered_within(20ms)) {
    ASSERT_TRUE(dripping.send("a"));
    ++dripped;
  }
  const std::string response = dripping.receive_all();
  EXPECT_EQ(status_of(response), 408) << response << " after " << dripped << " bytes";
  EXPECT_EQ(response.find(kPage), std::string::npos);
  // A connection that never says anything is closed at the deadline too.
  Client silent(server.port());
  EXPECT_EQ(silent.receive_all(), "");
}

TEST(LocalHttpServer, ConnectionsBeyondTheLimitAreAnswered503AtOnce) {
  ServerLimits limits = patient();
  limits.max_connections = 2;
  RunningServer server(limits);
  auto first = std::make_unique<Client>(server.port());
  Client second(server.port());
  ASSERT_TRUE(first->send("GET"));
  ASSERT_TRUE(second.send("GET"));
  // Accepted in order: the two above hold both places while this arrives.
  const std::string busy = exchange(server.port(), request("/", "localhost"));
  EXPECT_EQ(status_of(busy), 503) << busy;
  EXPECT_EQ(busy.find(kPage), std::string::npos);
  first.reset();  // a place frees once the server sees the close: then a request is served
  std::string response;
  while (status_of(response) != 200) {
    response = exchange(server.port(), request("/", "localhost"));
    ASSERT_TRUE(status_of(response) == 200 || status_of(response) == 503) << response;
  }
  EXPECT_EQ(body_of(response), kPage);
  EXPECT_NE(server.log().find("(more than 2 connections open: one answered 503)"), std::string::npos);
}

TEST(LocalHttpServer, RequestLinesAreLoggedWithoutTheirControlBytes) {
  RunningServer server(patient());
  EXPECT_EQ(status_of(exchange(server.port(), request("/\x1b]0;pwned\x07\x1b[2J", "localhost"))), 404);
  EXPECT_EQ(status_of(exchange(server.port(), request("/", "evil\x1b[2J.example"))), 403);
  const std::string log = server.log();
  EXPECT_NE(log.find("  GET /\\x1b]0;pwned\\x07\\x1b[2J HTTP/1.1\n"), std::string::npos) << log;
  EXPECT_NE(log.find("(Host evil\\x1b[2J.example refused: 403)"), std::string::npos) << log;
  for (const char c : log) {
    const auto byte = static_cast<unsigned char>(c);
    EXPECT_TRUE(c == '\n' || (byte >= 0x20 && byte < 0x7f)) << "byte " << int(byte) << " in the log:\n" << log;
  }
}

TEST(LocalHttpServer, StopsWhileAClientIsStillConnected) {
  RunningServer server(patient());
  Client stalled(server.port());
  ASSERT_TRUE(stalled.send("GET / HT"));
  const std::string response = exchange(server.port(), request("/", "localhost"));
  EXPECT_EQ(status_of(response), 200);
  server.stop();  // returns once the stalled connection's thread ended, long before its deadline
  EXPECT_EQ(stalled.receive_all(), "");
}

TEST(LocalHttpServer, APortInUseIsAClearError) {
  RunningServer server(patient());
  try {
    LocalHttpServer second(kPage, server.port());
    FAIL() << "a second server on port " << server.port();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(server.port())),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace umbra::cli
