// `umbra info MAP [--json]`: what a map file (.umb, .bt, .ot) holds.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "report.hpp"
#include "umbra/io/map_formats.hpp"

namespace umbra::cli {
namespace {

struct InfoOptions {
  std::string map_path;
  bool json = false;
};

int run_info(const InfoOptions& options) {
  const OccupancyMap map = load_any_map(options.map_path);  // .umb, .bt or .ot by extension
  const MapStatistics stats = compute_statistics(map);
  if (options.json) {
    std::printf("%s\n", statistics_json(stats).c_str());
  } else {
    std::printf("%s\n", options.map_path.c_str());
    print_statistics(stdout, stats);
  }
  return 0;
}

}  // namespace

Command add_info_command(CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand("info", "Show what a map file holds");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_flag("--json", options->json, "print one JSON object instead of text");
  add_memory_option(*command);
  return [options] { return run_info(*options); };
}

}  // namespace umbra::cli
