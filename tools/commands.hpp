// The subcommands of the `umbra` program. Each registers its options on the
// CLI11 app and returns the function that runs it (exit code 0 on success).
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace umbra::cli {

using Command = std::function<int()>;

Command add_demo_command(CLI::App& app);
Command add_build_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_convert_command(CLI::App& app);
Command add_query_command(CLI::App& app);
Command add_render_command(CLI::App& app);
Command add_view_command(CLI::App& app);

}  // namespace umbra::cli
