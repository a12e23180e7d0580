// umbra: build, inspect, convert, draw, view and demonstrate occupancy maps from the command line.
//
// Exit codes: 0 success, 1 bad input or failure (the message says what and
// where), 2 bad usage.
#include <cstdio>
#include <exception>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"umbra: probabilistic 3D occupancy maps with explicit unknown space"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "umbra 0.1.0");
  app.failure_message(CLI::FailureMessage::help);

  std::vector<umbra::cli::Command> commands;
  commands.push_back(umbra::cli::add_demo_command(app));
  commands.push_back(umbra::cli::add_build_command(app));
  commands.push_back(umbra::cli::add_info_command(app));
  commands.push_back(umbra::cli::add_convert_command(app));
  commands.push_back(umbra::cli::add_query_command(app));
  commands.push_back(umbra::cli::add_render_command(app));
  commands.push_back(umbra::cli::add_view_command(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    std::size_t index = 0;
    for (CLI::App* sub : app.get_subcommands({})) {
      if (sub->parsed()) return commands.at(index)();
      ++index;
    }
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra: error: %s\n", e.what());
    return 1;
  }
}
