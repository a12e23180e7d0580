// The umbra program as the command-line tests run it: its path (the test
// target defines UMBRA_CLI_PATH), paths quoted for the shell, and a run of
// `umbra ARGUMENTS` with its exit code and output.
#pragma once

#include <filesystem>
#include <string>

#include "support/test_support.hpp"

#ifndef UMBRA_CLI_PATH
#error "the test target must define UMBRA_CLI_PATH, the path of the umbra program"
#endif

namespace umbra::test {

inline std::string cli() { return UMBRA_CLI_PATH; }
inline std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }
inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
/// Runs `umbra ARGUMENTS` through the shell.
inline CommandResult run(const std::string& arguments) { return run_command(cli() + " " + arguments); }

}  // namespace umbra::test
