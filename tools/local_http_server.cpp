#include "local_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include "printable_text.hpp"

namespace umbra::cli {

namespace {

using Clock = std::chrono::steady_clock;

/// How often a wait looks at the stop flag.
constexpr std::chrono::milliseconds kStopCheck{100};
/// The longest request head read; a longer one is answered 431.
constexpr std::size_t kMaxHead = 16384;
/// The most of a request line printed to the log.
constexpr std::size_t kMaxLogged = 200;

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error("umbra view --serve: " + what + ": " + std::strerror(errno));
}

/// Waits until `fd` is ready for `events`: false when the deadline passed or
/// `stop` became true first.
bool wait_ready(int fd, short events, Clock::time_point deadline, const std::atomic<bool>& stop) {
  for (;;) {
    if (stop) return false;
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return false;
    pollfd ready{fd, events, 0};
    const int n = ::poll(&ready, 1, static_cast<int>(std::min(left, kStopCheck).count()));
    if (n > 0) return true;  // ready, or an error / hang-up that the next recv or send reports
    if (n < 0 && errno != EINTR) return false;
  }
}

/// Sends all of `bytes` before the deadline; false when the client went
/// away, stopped reading or the server stops.
bool send_all(int fd, std::string_view bytes, Clock::time_point deadline, const std::atomic<bool>& stop) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n > 0) {
      bytes.remove_prefix(static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      if (!wait_ready(fd, POLLOUT, deadline, stop)) return false;
    } else {
      return false;
    }
  }
  return true;
}

enum class HeadStatus { complete, nothing, timed_out, too_large, stopped };

/// Reads the request head (up to its blank line) into `head` before the
/// deadline. A client that closes after a line still gets an answer.
HeadStatus read_head(int fd, std::string& head, Clock::time_point deadline, const std::atomic<bool>& stop) {
  char buffer[4096];
  for (;;) {
    if (head.find("\r\n\r\n") != std::string::npos || head.find("\n\n") != std::string::npos) {
      return HeadStatus::complete;
    }
    if (head.size() > kMaxHead) return HeadStatus::too_large;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      head.append(buffer, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      if (wait_ready(fd, POLLIN, deadline, stop)) continue;
      if (stop) return HeadStatus::stopped;
      return head.empty() ? HeadStatus::nothing : HeadStatus::timed_out;
    } else {  // closed or reset
      return head.find('\n') == std::string::npos ? HeadStatus::nothing : HeadStatus::complete;
    }
  }
}

std::string response(int status, const char* reason, const char* type, std::size_t length) {
  return "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\nContent-Type: " + type +
         "\r\nContent-Length: " + std::to_string(length) + "\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
}

std::string text_response(int status, const char* reason, const std::string& body, bool with_body = true) {
  return response(status, reason, "text/plain; charset=utf-8", body.size()) + (with_body ? body : "");
}

bool equal_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return (x >= 'A' && x <= 'Z' ? x - 'A' + 'a' : x) == (y >= 'A' && y <= 'Z' ? y - 'A' + 'a' : y);
         });
}

/// The values of the head's Host fields (HTTP allows exactly one).
std::vector<std::string_view> host_fields(std::string_view head) {
  std::vector<std::string_view> values;
  std::size_t at = head.find('\n');  // the request line is not a field
  while (at != std::string_view::npos && at + 1 < head.size()) {
    const std::size_t start = at + 1;
    at = head.find('\n', start);
    std::string_view line = head.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos || !equal_ignoring_case(line.substr(0, colon), "host")) continue;
    std::string_view value = line.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
    while (!value.empty() && (value.back() == ' ' || value.back() == '\t')) value.remove_suffix(1);
    values.push_back(value);
  }
  return values;
}

/// Whether a Host names this machine's loopback address: 127.0.0.1,
/// localhost or [::1], each with or without ":port".
bool host_is_loopback(std::string_view host) {
  std::string_view name = host;
  std::string_view port;
  const std::size_t colon = host.rfind(':');
  if (colon != std::string_view::npos && host.find(']', colon) == std::string_view::npos) {
    name = host.substr(0, colon);
    port = host.substr(colon + 1);
    if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), [](char c) {
          return c >= '0' && c <= '9';
        })) {
      return false;
    }
  }
  return name == "127.0.0.1" || name == "[::1]" || equal_ignoring_case(name, "localhost");
}

}  // namespace

LocalHttpServer::LocalHttpServer(std::string page, int port, ServerLimits limits)
    : page_(std::move(page)), limits_(limits) {
  if (port < 0 || port > 65535) throw std::invalid_argument("umbra view: --port must be in [0, 65535]");
  listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listener_ < 0) fail("cannot open a socket");
  const int yes = 1;
  ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(listener_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int error = errno;
    ::close(listener_);
    errno = error;
    fail("cannot listen on 127.0.0.1:" + std::to_string(port));
  }
  if (::listen(listener_, 64) != 0) {
    const int error = errno;
    ::close(listener_);
    errno = error;
    fail("cannot listen");
  }
  socklen_t length = sizeof address;
  ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
}

LocalHttpServer::~LocalHttpServer() { ::close(listener_); }

void LocalHttpServer::serve(std::FILE* log, const std::atomic<bool>& stop) {
  while (!stop) {
    pollfd ready{listener_, POLLIN, 0};
    if (::poll(&ready, 1, static_cast<int>(kStopCheck.count())) <= 0) continue;  // a timeout or a signal
    const int client = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (client >= 0) {
      start_connection(client, log, stop);
    } else if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
      // Out of descriptors or memory: the connection waits in the queue
      // until one of ours ends, rather than the loop spinning on it.
      std::unique_lock lock(mutex_);
      connection_ended_.wait_for(lock, kStopCheck);
    } else if (errno == EBADF || errno == EINVAL || errno == ENOTSOCK || errno == EFAULT) {  // the listener broke
      const int error = errno;
      std::unique_lock lock(mutex_);  // the connections use this object: let them end first
      connection_ended_.wait(lock, [this] { return open_connections_ == 0; });
      errno = error;
      fail("accept failed");
    }  // else a client's own network error (accept(2) passes them on) or EINTR: on to the next
  }
  std::unique_lock lock(mutex_);
  connection_ended_.wait(lock, [this] { return open_connections_ == 0; });
}

void LocalHttpServer::start_connection(int client, std::FILE* log, const std::atomic<bool>& stop) {
  {
    std::lock_guard lock(mutex_);
    if (open_connections_ < limits_.max_connections) {
      ++open_connections_;
      try {
        std::thread([this, client, log, &stop] {
          answer_connection(client, log, stop);
          ::close(client);
          std::lock_guard ended(mutex_);
          --open_connections_;
          connection_ended_.notify_all();  // under the lock: serve() may destroy the server once it sees 0
        }).detach();
        return;
      } catch (const std::system_error&) {  // the system refused a thread: as if the limit were reached
        --open_connections_;
      }
    }
  }
  // The socket's send buffer takes these few bytes at once: no wait.
  const std::string busy = text_response(503, "Service Unavailable",
                                         "more than " + std::to_string(limits_.max_connections) +
                                             " connections are open; try again in a moment\n");
  (void)::send(client, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::close(client);
  std::fprintf(log, "  (more than %zu connections open: one answered 503)\n", limits_.max_connections);
  std::fflush(log);
}

void LocalHttpServer::answer_connection(int client, std::FILE* log, const std::atomic<bool>& stop) {
  std::string head;
  const HeadStatus status = read_head(client, head, Clock::now() + limits_.head_deadline, stop);
  const auto send_deadline = Clock::now() + limits_.send_deadline;
  auto send = [&](const std::string& bytes) { return send_all(client, bytes, send_deadline, stop); };
  // An idle connection (browsers open some in advance), or the server stops.
  if (status == HeadStatus::nothing || status == HeadStatus::stopped) return;
  const std::string line = head.substr(0, head.find_first_of("\r\n"));
  // One fprintf per line: the lines of connections served at once do not mix.
  auto print = [&](const std::string& note) {
    std::fprintf(log, "  %s%s\n", printable(line, kMaxLogged).c_str(), note.c_str());
    std::fflush(log);
  };
  if (status == HeadStatus::timed_out) {
    print(" (request not finished within the deadline: 408)");
    send(text_response(408, "Request Timeout", "the request did not arrive in time\n"));
    return;
  }
  if (status == HeadStatus::too_large) {
    print(" (request head over 16 KiB: 431)");
    send(text_response(431, "Request Header Fields Too Large", "the request head is over 16 KiB\n"));
    return;
  }
  const std::size_t space = line.find(' ');
  const std::string method = line.substr(0, space);
  const std::string target =
      space == std::string::npos ? "" : line.substr(space + 1, line.find(' ', space + 1) - space - 1);
  const std::vector<std::string_view> hosts = host_fields(head);
  if (hosts.size() != 1) {
    print(hosts.empty() ? " (no Host: 400)" : " (several Hosts: 400)");
    send(text_response(400, "Bad Request", "a request must name one Host\n"));
    return;
  }
  if (!host_is_loopback(hosts.front())) {
    print(" (Host " + printable(hosts.front(), kMaxLogged) + " refused: 403)");
    send(text_response(403, "Forbidden", "this server answers only requests for 127.0.0.1, localhost or [::1]\n"));
    return;
  }
  print("");
  if (method != "GET" && method != "HEAD") {
    send(text_response(405, "Method Not Allowed", "only GET and HEAD\n"));
  } else if (target != "/" && target != "/index.html") {
    send(text_response(404, "Not Found", "not found: this server has only the map's page at /\n", method == "GET"));
  } else if (send(response(200, "OK", "text/html; charset=utf-8", page_.size())) && method == "GET") {
    send(page_);
  }
}

namespace {

std::atomic<bool> g_stop{false};  // lock-free, so a signal handler may set it
static_assert(std::atomic<bool>::is_always_lock_free);

void request_stop(int) { g_stop = true; }

}  // namespace

void serve_page(const std::string& page, int port, std::FILE* log) {
  LocalHttpServer server(page, port);
  struct sigaction stop {};
  stop.sa_handler = request_stop;
  sigemptyset(&stop.sa_mask);
  struct sigaction old_int {};
  struct sigaction old_term {};
  ::sigaction(SIGINT, &stop, &old_int);
  ::sigaction(SIGTERM, &stop, &old_term);
  g_stop = false;

  std::fprintf(log, "serving http://127.0.0.1:%d/ (Ctrl-C to stop)\n", server.port());
  std::fflush(log);
  try {
    server.serve(log, g_stop);
  } catch (...) {
    ::sigaction(SIGINT, &old_int, nullptr);
    ::sigaction(SIGTERM, &old_term, nullptr);
    throw;
  }
  ::sigaction(SIGINT, &old_int, nullptr);
  ::sigaction(SIGTERM, &old_term, nullptr);
  std::fprintf(log, "stopped\n");
}

}  // namespace umbra::cli
