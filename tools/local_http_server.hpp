// A minimal HTTP server for one page on this machine's loopback address
// (`umbra view --serve`).
//
// It answers GET and HEAD of "/" and "/index.html" with the page and
// anything else with 404 (405 for other methods), one connection at a time,
// "Connection: close". It listens on 127.0.0.1 only, so nothing outside the
// machine can reach it, and runs until SIGINT or SIGTERM (Ctrl-C). A client
// that sends nothing for 5 s is dropped. Cost: one read and one write of the
// page per request; no threads.
#pragma once

#include <cstdio>
#include <string>

namespace umbra::cli {

/// Serves `page` on 127.0.0.1:`port` (0: a free port the system picks)
/// until interrupted. Prints "serving http://127.0.0.1:PORT/" and a line per
/// request to `log`. Throws std::runtime_error when the port cannot be used.
void serve_page(const std::string& page, int port, std::FILE* log);

}  // namespace umbra::cli
