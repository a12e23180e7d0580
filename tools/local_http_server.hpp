// A minimal HTTP server for one page on this machine's loopback address
// (`umbra view --serve`).
//
// It answers GET and HEAD of "/" and "/index.html" with the page and
// anything else with 404 (405 for other methods), "Connection: close". It
// listens on 127.0.0.1 only, so nothing outside the machine can reach it,
// and answers only requests whose Host is 127.0.0.1, localhost or [::1]
// (with any port; 403 otherwise, 400 without one): a page on another site
// that makes its own name resolve to 127.0.0.1 (DNS rebinding) sends its own
// name as Host and gets nothing. Every connection has a thread of its own,
// so a slow or idle client delays nobody else; each has a deadline for its
// whole request head (5 s from the connection: 408, then closed) and for
// sending the answer (60 s), however slowly its bytes come. At most 32
// connections are open at once; one more is answered 503 at once and
// closed. Request lines are printed with bytes outside printable ASCII as
// \xNN, so a request cannot send escape sequences to the terminal.
// Cost: one read and one write of the page per request, one thread per open
// connection; an idle server wakes every 100 ms to see whether it must stop.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>

namespace umbra::cli {

/// The bounds of LocalHttpServer (the tests shorten or lengthen them).
struct ServerLimits {
  std::size_t max_connections = 32;
  std::chrono::milliseconds head_deadline{5000};   ///< from the connection to the end of its request head
  std::chrono::milliseconds send_deadline{60000};  ///< for the whole answer
};

class LocalHttpServer {
 public:
  /// Listens on 127.0.0.1:`port` (0: a free port the system picks). Throws
  /// std::runtime_error when the port cannot be used.
  LocalHttpServer(std::string page, int port, ServerLimits limits = {});
  ~LocalHttpServer();
  LocalHttpServer(const LocalHttpServer&) = delete;
  LocalHttpServer& operator=(const LocalHttpServer&) = delete;

  /// The port listened on.
  [[nodiscard]] int port() const { return port_; }

  /// Answers connections, printing a line per request to `log`, until `stop`
  /// is true (looked at every 100 ms), then waits for the connections still
  /// open: each ends within 100 ms of `stop`.
  void serve(std::FILE* log, const std::atomic<bool>& stop);

 private:
  void answer_connection(int client, std::FILE* log, const std::atomic<bool>& stop);
  /// Starts a thread for the connection, or answers 503 when there are too many.
  void start_connection(int client, std::FILE* log, const std::atomic<bool>& stop);

  std::string page_;
  ServerLimits limits_;
  int listener_ = -1;
  int port_ = 0;
  std::mutex mutex_;
  std::condition_variable connection_ended_;
  std::size_t open_connections_ = 0;  ///< guarded by mutex_
};

/// Serves `page` on 127.0.0.1:`port` (0: a free port the system picks)
/// until SIGINT or SIGTERM (Ctrl-C). Prints "serving http://127.0.0.1:PORT/"
/// and a line per request to `log`. Throws std::runtime_error when the port
/// cannot be used.
void serve_page(const std::string& page, int port, std::FILE* log);

}  // namespace umbra::cli
