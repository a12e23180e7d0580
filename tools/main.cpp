// umbra: build, inspect, convert, crop, merge, compare, export, draw, view,
// project to 2D and demonstrate occupancy maps from the command line.
//
// Exit codes (commands.hpp, `umbra --help`, README "Errors and limits"): 0
// success, 1 an input or the system failed (a missing, unreadable or
// malformed file; the message names it), 2 bad usage, 3 build --keep-going
// saved a map without what it skipped; a signal ends the program as usual
// (128 + its number) after removing an unfinished save.
//
// A usage error is two lines on stderr: what is wrong, naming the option and
// the value as typed, then where the help is. The help itself is not
// printed: 14 to 38 lines of it would push the one line that matters off
// the screen.
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "commands.hpp"
#include "signals.hpp"
#ifdef UMBRA_WITH_ROS
#include "umbra_ros/rosbag_source.hpp"
#endif

namespace {

/// "umbra" or "umbra build": the command whose help a user should read.
std::string command_name(const CLI::App& app) {
  std::string name = "umbra";
  for (const CLI::App* sub : app.get_subcommands()) name += " " + sub->get_name();
  return name;
}

/// The two lines of a usage error (CLI11's own errors and umbra's UsageError alike).
std::string usage_error_text(const CLI::App& app, const std::string& what) {
  return "umbra: error: " + what + "\nRun `" + command_name(app) + " --help` for the options.\n";
}

bool is_command(const CLI::App& app, const std::string& name) {
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == name) return true;
  }
  return false;
}

/// "demo, build, info, ..."
std::string command_names(const CLI::App& app) {
  std::string names;
  for (const CLI::App* sub : app.get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
  return names;
}

constexpr const char* kExitCodes =
    "Exit codes: 0 success; 1 an input or the system failed (a missing, unreadable or malformed file, an I/O "
    "error, the memory limit: the message names the file, and nothing is saved); 2 bad usage (an option or "
    "argument is wrong: nothing is read); 3 build --keep-going skipped an input or scan and saved the rest.\n"
    "Run `umbra COMMAND --help` for a command's options.";

}  // namespace

int main(int argc, char** argv) {
  umbra::cli::remove_unfinished_saves_on_signals();
#ifdef UMBRA_WITH_ROS
  umbra::ros_io::register_rosbag_format();  // .bag inputs of `umbra build`
#endif
  CLI::App app{"umbra: probabilistic 3D occupancy maps with explicit unknown space"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "umbra 0.1.0");
  app.footer(kExitCodes);
  app.failure_message([](const CLI::App* failed, const CLI::Error& e) { return usage_error_text(*failed, e.what()); });

  std::vector<umbra::cli::Command> commands;
  commands.push_back(umbra::cli::add_demo_command(app));
  commands.push_back(umbra::cli::add_build_command(app));
  commands.push_back(umbra::cli::add_info_command(app));
  commands.push_back(umbra::cli::add_convert_command(app));
  commands.push_back(umbra::cli::add_crop_command(app));
  commands.push_back(umbra::cli::add_merge_command(app));
  commands.push_back(umbra::cli::add_compare_command(app));
  commands.push_back(umbra::cli::add_export_command(app));
  commands.push_back(umbra::cli::add_query_command(app));
  commands.push_back(umbra::cli::add_render_command(app));
  commands.push_back(umbra::cli::add_view_command(app));
  commands.push_back(umbra::cli::add_project_command(app));

  // CLI11 would say "A subcommand is required" for a misspelt one.
  if (argc >= 2 && argv[1][0] != '-' && !is_command(app, argv[1])) {
    std::fputs(usage_error_text(app, "unknown command '" + std::string(argv[1]) + "' (the commands: " +
                                         command_names(app) + ")")
                   .c_str(),
               stderr);
    return umbra::cli::kBadUsage;
  }
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
    std::fputs(usage_error_text(app, e.what()).c_str(), stderr);
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
