// `umbra merge A B [C ...] -o OUT [--offset X Y Z | --transform ...]`: maps of
// several robots or runs added into one (OccupancyMap::merge).
//
// The first map is the base: B, C, ... are added to it in order, each placed
// by the same --offset (whole voxels) or --transform (metres and a unit
// quaternion, the other maps' frame to the first's). The output keeps the
// first map's sensor model, thresholds and color. Inputs may be .umb, .bt or
// .ot (OctoMap files carry no sensor model: the default one clamps them, as
// when they are loaded anywhere else), or a moving window's spill file
// (.umbs, umbra/io/spill_file.hpp: its pieces added up first). Cost: each
// load, one walk over each added map's known nodes, one save.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "map_output.hpp"
#include "options.hpp"
#include "report.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_formats.hpp"
#include "umbra/io/spill_file.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::cli {
namespace {

struct MergeOptions {
  std::vector<std::string> inputs;
  std::string output;
  std::vector<std::int64_t> offset;  // empty or x y z
  std::vector<double> transform;     // empty or x y z qw qx qy qz
};

bool is_spill_file(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".umbs";
}

OccupancyMap load_input(const std::filesystem::path& path) {
  return is_spill_file(path) ? load_spill(path) : load_any_map(path);
}

int run_merge(const MergeOptions& options) {
  const std::optional<Pose> transform = as_usage([&]() -> std::optional<Pose> {
    if (options.transform.empty()) return std::nullopt;
    const auto& t = options.transform;
    try {
      return Pose::from_translation_quaternion(t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(std::string("--transform: ") + error.what());
    }
  });
  const VoxelOffset offset =
      options.offset.empty() ? VoxelOffset{} : VoxelOffset{options.offset[0], options.offset[1], options.offset[2]};
  check_can_save(options.output);  // before the (maybe long) loads
  OccupancyMap merged = load_input(options.inputs.front());
  (void)check_map_output(options.output, merged.depth_levels(), "output");
  std::printf("base %s: %.4g m voxels, %d depth levels\n", options.inputs.front().c_str(), merged.resolution(),
              merged.depth_levels());
  for (std::size_t i = 1; i < options.inputs.size(); ++i) {
    const std::string& path = options.inputs[i];
    const OccupancyMap other = load_input(path);
    MergeStats stats;
    try {
      stats = transform ? merged.merge(other, *transform) : merged.merge(other, offset);
    } catch (const std::invalid_argument& error) {
      throw std::runtime_error(path + ": cannot be merged into " + options.inputs.front() + ": " + error.what());
    } catch (const std::out_of_range& error) {
      throw std::runtime_error(path + ": cannot be merged into " + options.inputs.front() + ": " + error.what());
    }
    std::printf("added %s: %llu voxels in %llu nodes\n", path.c_str(),
                static_cast<unsigned long long>(stats.voxels), static_cast<unsigned long long>(stats.nodes));
  }
  const MapFileFormat base_format =
      is_spill_file(options.inputs.front()) ? MapFileFormat::umb : map_file_format_for(options.inputs.front());
  print_format_notes(merged, base_format, map_file_format_for(options.output));
  save_map_as(merged, options.output);
  std::printf("wrote %s (%ju bytes)\n", options.output.c_str(), std::filesystem::file_size(options.output));
  print_statistics(stdout, compute_statistics(merged));
  return kSuccess;
}

}  // namespace

Command add_merge_command(CLI::App& app) {
  auto options = std::make_shared<MergeOptions>();
  CLI::App* command = app.add_subcommand(
      "merge", "Add maps of other robots or runs into the first map (log-odds summed voxel by voxel, clamped)");
  command
      ->add_option("inputs", options->inputs,
                   "maps to merge, the first is the base (.umb, .bt, .ot; .umbs: a moving window's spill file)")
      ->required()
      ->expected(2, -1)
      ->check(CLI::Validator(
          [](std::string& name) { return is_spill_file(name) ? std::string() : map_extension()(name); },
          "MAP(.umb|.bt|.ot|.umbs)"));
  command->add_option("-o,--output", options->output, "map to write (.umb, .bt, .ot); replaced atomically")
      ->required()
      ->check(map_extension());
  CLI::Option* offset = command->add_option(
      "--offset", options->offset, "X Y Z: the added maps' voxel k lands on the base's voxel k + (X, Y, Z)");
  offset->expected(3);
  CLI::Option* transform = command->add_option(
      "--transform", options->transform,
      "X Y Z QW QX QY QZ: the added maps' frame to the base's (metres, unit quaternion); each base voxel takes "
      "the added voxel its centre maps back into");
  transform->expected(7);
  offset->excludes(transform);
  add_memory_option(*command);
  return [options] { return run_merge(*options); };
}

}  // namespace umbra::cli
