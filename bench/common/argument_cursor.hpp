// The benchmarks' command lines: "--flag value" pairs read in order; a flag
// missing its value ends the program with a message and exit code 2.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

namespace umbra_bench {

struct ArgumentCursor {
  int argc;
  char** argv;
  int at = 0;

  /// Moves to the next argument; false past the last.
  bool next() { return ++at < argc; }
  [[nodiscard]] std::string flag() const { return argv[at]; }
  /// The value after the current flag (and moves past it).
  std::string value() {
    if (at + 1 >= argc) {
      std::fprintf(stderr, "%s needs a value\n", argv[at]);
      std::exit(2);
    }
    return argv[++at];
  }
};

}  // namespace umbra_bench
