// `umbra info MAP [--json]`: what a map file (.umb, .bt, .ot) holds.
//
// Besides the statistics every command prints, the node count liboctomap
// would give for the same map (report.hpp, octomap_node_count): umbra's own
// count is larger because a node with children keeps all eight, unknown
// ones included, where OctoMap leaves unobserved children out.
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
  const std::size_t octomap_nodes = octomap_node_count(map);
  if (options.json) {
    std::printf("%s\n", statistics_json(stats, ", \"octomap_nodes\": " + std::to_string(octomap_nodes)).c_str());
  } else {
    std::printf("%s\n", options.map_path.c_str());
    print_statistics(stdout, stats);
    std::printf("  OctoMap nodes     %zu (liboctomap's count for this map: it stores no unknown children, where "
                "umbra keeps all eight of a node's children)\n",
                octomap_nodes);
  }
  return 0;
}

}  // namespace

Command add_info_command(CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand(
      "info", "Show what a map file holds: resolution, nodes, memory, occupied and free voxels and volumes, bounds");
  command->add_option("map", options->map_path, "map file (.umb, or OctoMap's .bt / .ot)")
      ->required();  // a missing file is an input failure (exit code 1), named when it is loaded
  command->add_flag("--json", options->json, "print one JSON object instead of text");
  command->footer(
      "Nodes: umbra counts every node of its tree: a node with children has all eight, unknown (never observed) "
      "ones included, so that unknown space is explicit. OctoMap leaves unobserved children out, so liboctomap's "
      "size() for the same map is smaller: the line 'OctoMap nodes' (JSON: octomap_nodes) gives that count, the "
      "nodes whose subtree holds an observed voxel. Voxel counts and volumes are in finest voxels: a pruned node "
      "counts for every voxel it covers.");
  add_memory_option(*command);
  return [options] { return run_info(*options); };
}

}  // namespace umbra::cli
