// `umbra project MAP -o map.pgm --z-min 0.1 --z-max 1.8 [--depth D] [--rule R]`:
// the map projected between two heights as a 2D navigation grid, written as
// map_server's PGM + YAML (map.pgm and map.yaml beside it), which ROS's
// map_server and Nav2 load as a static map.
//
// The cells and rules are umbra/query/navigation_grid.hpp's, the files
// umbra/io/navigation_grid_files.hpp's (both written atomically). Usage
// errors (a bad height, z_min >= z_max, an unknown rule, an output that is
// not .pgm) are found before the map is read; an output folder that cannot
// be written is found before it is read too. Cost: one load, two walks over
// the nodes in the band, one byte per cell written.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/navigation_grid_files.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra::cli {
namespace {

struct ProjectCommandOptions {
  std::string input;
  std::string output;
  double z_min = 0.0;
  double z_max = 0.0;
  int depth = 0;
  std::string rule = "all_known";
};

int run_project(const ProjectCommandOptions& options) {
  ProjectionOptions projection;
  projection.z_min = options.z_min;
  projection.z_max = options.z_max;
  projection.depth = options.depth;
  const std::filesystem::path yaml_path = as_usage([&] {
    projection.rule = parse_projection_rule(options.rule);
    projection.validate();
    return navigation_grid_yaml_path(options.output);
  });
  check_can_save(options.output);  // before the (maybe long) load
  check_can_save(yaml_path);
  const OccupancyMap map = load_any_map(options.input);
  if (projection.depth > map.depth_levels()) {
    throw UsageError("--depth " + std::to_string(projection.depth) + " is outside [0, " +
                     std::to_string(map.depth_levels()) + "] for " + options.input);
  }
  const NavigationGrid grid = as_usage([&] {
    try {
      return project_to_grid(map, projection);
    } catch (const std::out_of_range& e) {  // the band lies outside this map: the heights are wrong
      throw UsageError(e.what());
    }
  });
  if (grid.empty()) {
    std::fprintf(stderr, "umbra: %s has no known voxel between z %g and %g m: no grid to write\n",
                 options.input.c_str(), options.z_min, options.z_max);
    return kFailure;
  }
  (void)save_navigation_grid(grid, options.output);
  std::size_t counts[3] = {0, 0, 0};  // occupied, free, unknown
  for (const GridCell cell : grid.cells) ++counts[cell == GridCell::occupied ? 0 : cell == GridCell::free ? 1 : 2];
  std::printf("projected z %g .. %g m (rule %s) onto %u x %u cells of %g m, origin (%g, %g): %zu occupied, %zu free, "
              "%zu unknown\n",
              options.z_min, options.z_max, options.rule.c_str(), grid.width, grid.height, grid.resolution,
              grid.origin_x, grid.origin_y, counts[0], counts[1], counts[2]);
  std::printf("wrote %s and %s\n", options.output.c_str(), yaml_path.string().c_str());
  return kSuccess;
}

}  // namespace

Command add_project_command(CLI::App& app) {
  auto options = std::make_shared<ProjectCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "project", "Project a map between two heights onto a 2D navigation grid (map_server's PGM + YAML)");
  command->add_option("input", options->input, "map to read (.umb, .bt, .ot)")->required()->check(map_extension());
  command
      ->add_option("-o,--output", options->output,
                   "picture to write (.pgm); its YAML description goes beside it (.yaml); both replaced atomically")
      ->required();
  command
      ->add_option("--z-min", options->z_min,
                   "lower height of the band (metres): the voxel rows from the one holding z-min to the one holding "
                   "z-max count (a height on a voxel face takes the voxel above it)")
      ->required()
      ->check(number_in(-1e9, 1e9, "a height in metres"));
  command->add_option("--z-max", options->z_max, "upper height of the band (metres), above --z-min")
      ->required()
      ->check(number_in(-1e9, 1e9, "a height in metres"));
  command->add_option("--depth", options->depth, "cells are columns of nodes of this depth (0: finest voxels)")
      ->capture_default_str()
      ->check(CLI::Range(0, 21));
  command
      ->add_option("--rule", options->rule,
                   "when a cell without occupied voxels is free: all_known (every voxel of its band is free; the "
                   "default) or any_free (at least one is, as octomap_server's projected_map)")
      ->capture_default_str();
  add_memory_option(*command);
  return [options] { return run_project(*options); };
}

}  // namespace umbra::cli
