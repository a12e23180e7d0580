#include "local_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace umbra::cli {

namespace {

volatile sig_atomic_t g_stop = 0;

void request_stop(int) { g_stop = 1; }

/// Closes a descriptor when it goes out of scope.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  [[nodiscard]] int get() const { return fd_; }

 private:
  int fd_;
};

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error("umbra view --serve: " + what + ": " + std::strerror(errno));
}

void send_all(int fd, const std::string& bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR && !g_stop) continue;
    if (n <= 0) return;  // the client went away: nothing to do
    sent += std::size_t(n);
  }
}

/// The request head (up to the blank line, at most 16 KiB), or "" when the
/// client closed or timed out first.
std::string read_head(int fd) {
  std::string head;
  char buffer[4096];
  while (head.find("\r\n\r\n") == std::string::npos && head.size() < 16384) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n < 0 && errno == EINTR && !g_stop) continue;
    if (n <= 0) return head.find('\n') == std::string::npos ? std::string() : head;
    head.append(buffer, std::size_t(n));
  }
  return head;
}

std::string response(int status, const char* reason, const char* type, std::size_t length) {
  return "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\nContent-Type: " + type +
         "\r\nContent-Length: " + std::to_string(length) + "\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
}

void answer(int client, const std::string& page, std::FILE* log) {
  const std::string head = read_head(client);
  if (head.empty()) return;
  const std::string line = head.substr(0, head.find_first_of("\r\n"));
  const std::size_t space = line.find(' ');
  const std::string method = line.substr(0, space);
  const std::string target = space == std::string::npos ? "" : line.substr(space + 1, line.find(' ', space + 1) - space - 1);
  std::fprintf(log, "  %s\n", line.c_str());
  std::fflush(log);
  if (method != "GET" && method != "HEAD") {
    const std::string body = "only GET and HEAD\n";
    send_all(client, response(405, "Method Not Allowed", "text/plain", body.size()) + body);
  } else if (target != "/" && target != "/index.html") {
    const std::string body = "not found: this server has only the map's page at /\n";
    send_all(client, response(404, "Not Found", "text/plain", body.size()) + (method == "GET" ? body : ""));
  } else {
    send_all(client, response(200, "OK", "text/html; charset=utf-8", page.size()));
    if (method == "GET") send_all(client, page);
  }
}

}  // namespace

void serve_page(const std::string& page, int port, std::FILE* log) {
  if (port < 0 || port > 65535) throw std::invalid_argument("umbra view: --port must be in [0, 65535]");
  const Descriptor server(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  if (server.get() < 0) fail("cannot open a socket");
  const int yes = 1;
  ::setsockopt(server.get(), SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(server.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    fail("cannot listen on 127.0.0.1:" + std::to_string(port));
  }
  if (::listen(server.get(), 16) != 0) fail("cannot listen");
  socklen_t length = sizeof address;
  ::getsockname(server.get(), reinterpret_cast<sockaddr*>(&address), &length);

  // Ctrl-C interrupts accept() (no SA_RESTART) and ends the loop.
  struct sigaction stop {};
  stop.sa_handler = request_stop;
  sigemptyset(&stop.sa_mask);
  struct sigaction old_int {};
  struct sigaction old_term {};
  ::sigaction(SIGINT, &stop, &old_int);
  ::sigaction(SIGTERM, &stop, &old_term);
  g_stop = 0;

  std::fprintf(log, "serving http://127.0.0.1:%d/ (Ctrl-C to stop)\n", int(ntohs(address.sin_port)));
  std::fflush(log);
  while (!g_stop) {
    const Descriptor client(::accept4(server.get(), nullptr, nullptr, SOCK_CLOEXEC));
    if (client.get() < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      fail("accept failed");
    }
    timeval timeout{5, 0};
    ::setsockopt(client.get(), SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    ::setsockopt(client.get(), SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    answer(client.get(), page, log);
  }
  ::sigaction(SIGINT, &old_int, nullptr);
  ::sigaction(SIGTERM, &old_term, nullptr);
  std::fprintf(log, "stopped\n");
}

}  // namespace umbra::cli
