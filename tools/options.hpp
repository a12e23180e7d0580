// Option values shared by the subcommands: checks that turn non-physical
// values into usage errors (exit code 2) with the range in the message, and
// --max-memory. Cost: nothing worth measuring (runs once per option).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "umbra/core/aabb.hpp"

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

/// `count` finite numbers separated by commas; otherwise std::invalid_argument
/// naming `option` (empty: left to CLI11, which names it) and the text as typed.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& option);

/// "minx,miny,minz,maxx,maxy,maxz" as a valid box (min <= max); otherwise
/// std::invalid_argument naming `option` and the text.
Aabb parse_box(const std::string& text, const std::string& option);

/// CLI11 check: a box as parse_box() reads it.
CLI::Validator box_check();

/// CLI11 check: the name ends in a map file extension (.umb, .bt, .ot, any
/// case); the message names the extension and the known ones.
CLI::Validator map_extension();

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
