// `umbra crop IN -o OUT --bbox minx,miny,minz,maxx,maxy,maxz`: the part of a
// map inside a box, as a map file (OctoMap's edit_octree -bbx).
//
// The voxels the box meets keep their values and colors, the rest become
// unknown (umbra/map/map_crop.hpp; the box's voxels as voxel_box.hpp says).
// IN and OUT may be .umb, .bt or .ot. Cost: one load, one walk over the
// nodes in the box, one save.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "map_output.hpp"
#include "options.hpp"
#include "report.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/map/map_crop.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra::cli {
namespace {

struct CropOptions {
  std::string input;
  std::string output;
  std::string bbox;
};

int run_crop(const CropOptions& options) {
  const Aabb box = as_usage([&] { return parse_box(options.bbox, "--bbox"); });
  check_can_save(options.output);  // before the (maybe long) load
  const OccupancyMap map = load_any_map(options.input);
  (void)check_map_output(options.output, map.depth_levels(), "output");
  const VoxelBox keep = voxel_box(map.grid(), box);
  const OccupancyMap cropped = crop_map(map, keep);
  const MapStatistics before = compute_statistics(map);
  const MapStatistics after = compute_statistics(cropped);
  print_format_notes(cropped, map_file_format_for(options.input), map_file_format_for(options.output));
  save_map_as(cropped, options.output);
  const Vec3d low = map.grid().min_corner(keep.lo);
  const Vec3d high = map.grid().min_corner(keep.hi) + Vec3d{map.resolution(), map.resolution(), map.resolution()};
  std::printf("kept the voxels from (%g, %g, %g) to (%g, %g, %g) m: %llu of %llu occupied and %llu of %llu free "
              "voxels\n",
              low.x, low.y, low.z, high.x, high.y, high.z, static_cast<unsigned long long>(after.occupied_voxels),
              static_cast<unsigned long long>(before.occupied_voxels),
              static_cast<unsigned long long>(after.free_voxels), static_cast<unsigned long long>(before.free_voxels));
  std::printf("wrote %s (%ju bytes)\n", options.output.c_str(), std::filesystem::file_size(options.output));
  print_statistics(stdout, after);
  return kSuccess;
}

}  // namespace

Command add_crop_command(CLI::App& app) {
  auto options = std::make_shared<CropOptions>();
  CLI::App* command = app.add_subcommand(
      "crop", "Keep the part of a map inside a box (voxel values and colors unchanged, the rest unknown)");
  command->add_option("input", options->input, "map to read (.umb, .bt, .ot)")->required()->check(map_extension());
  command->add_option("-o,--output", options->output, "map to write (.umb, .bt, .ot); replaced atomically")
      ->required()
      ->check(map_extension());
  command
      ->add_option("--bbox", options->bbox,
                   "minx,miny,minz,maxx,maxy,maxz in metres: every voxel the box meets is kept (a corner on a voxel "
                   "face takes the voxel above it, as OctoMap's coordToKey)")
      ->required()
      ->check(box_check());
  add_memory_option(*command);
  return [options] { return run_crop(*options); };
}

}  // namespace umbra::cli
