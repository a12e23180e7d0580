// The subcommands of the `umbra` program. Each registers its options on the
// CLI11 app and returns the function that runs it (exit code 0 on success).
#pragma once

#include <functional>
#include <stdexcept>

#include <CLI/CLI.hpp>

namespace umbra::cli {

using Command = std::function<int()>;

/// Exit codes (README, "Errors and limits").
enum ExitCode : int {
  kSuccess = 0,
  kFailure = 1,        ///< a missing, unreadable or bad input, I/O error, memory limit: the message names the
                       ///< file; nothing saved
  kBadUsage = 2,       ///< an option or argument is wrong: nothing read
  kSavedWithSkips = 3  ///< build --keep-going skipped an input or scan, and saved the rest
};

/// A wrong option or argument: main() prints it and exits with kBadUsage.
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

Command add_demo_command(CLI::App& app);
Command add_build_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_convert_command(CLI::App& app);
Command add_crop_command(CLI::App& app);
Command add_merge_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_export_command(CLI::App& app);
Command add_query_command(CLI::App& app);
Command add_render_command(CLI::App& app);
Command add_view_command(CLI::App& app);
Command add_project_command(CLI::App& app);

}  // namespace umbra::cli
