// umbra: build, inspect, convert, draw, view and demonstrate occupancy maps from the command line.
//
// Exit codes (commands.hpp, README "Errors and limits"): 0 success, 1 bad
// input or failure (the message says what and where), 2 bad usage, 3 build
// --keep-going saved a map without what it skipped; a signal ends the
// program as usual (128 + its number) after removing an unfinished save.
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "commands.hpp"
#include "signals.hpp"

int main(int argc, char** argv) {
  umbra::cli::remove_unfinished_saves_on_signals();
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
    return code == 0 ? umbra::cli::kSuccess : umbra::cli::kBadUsage;
  }
  try {
    std::size_t index = 0;
    for (CLI::App* sub : app.get_subcommands({})) {
      if (sub->parsed()) return commands.at(index)();
      ++index;
    }
    return umbra::cli::kBadUsage;
  } catch (const umbra::cli::UsageError& e) {
    std::fprintf(stderr, "umbra: error: %s\nRun with --help for more information.\n", e.what());
    return umbra::cli::kBadUsage;
  } catch (const std::bad_alloc& e) {
    // umbra's own (MemoryLimitError) name the file and the size; a bare one gets a sentence.
    const std::string what = e.what();
    std::fprintf(stderr, "umbra: error: %s\n",
                 what == std::bad_alloc().what() ? "out of memory (the map or an input is larger than this machine "
                                                   "can hold; see --max-memory)"
                                                 : what.c_str());
    return umbra::cli::kFailure;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra: error: %s\n", e.what());
    return umbra::cli::kFailure;
  }
}
