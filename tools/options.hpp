// Option values shared by the subcommands: checks that turn non-physical
// values into usage errors (exit code 2) with the range in the message, and
// --max-memory. Cost: nothing worth measuring (runs once per option).
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "commands.hpp"

namespace umbra::cli {

/// CLI11 check: a number in [low, high] (NaN and infinities refused); the
/// message ("--res: WHAT must be a number in [LOW, HIGH], got 'TEXT'") says
/// what the value is, the range, and the value as typed.
CLI::Validator number_in(double low, double high, const std::string& what);

/// CLI11 check: a number that is not NaN (infinities allowed).
CLI::Validator not_nan();

/// Adds --max-memory SIZE to `command`: sets umbra's memory limit
/// (umbra/core/memory_limit.hpp) when the command runs.
void add_memory_option(CLI::App& command);

/// "512M", "2G", "1.5GiB", "100000" (bytes; K, M, G, T are powers of 1024,
/// an optional "iB" or "B" after them); throws UsageError otherwise.
std::uint64_t parse_size(const std::string& text);

/// Runs `check` (which validates options); std::invalid_argument from it
/// becomes a UsageError with the same message.
template <typename Check>
decltype(auto) as_usage(Check&& check) {
  try {
    return std::forward<Check>(check)();
  } catch (const UsageError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

}  // namespace umbra::cli
