// `umbra export IN -o OUT.ply [--mesh] [--color]`: the occupied voxels of a
// map as a PLY point cloud or a mesh of cubes (OctoMap's octree2pointcloud
// and bt2vrml), for tools that load PLY. The file's layout: ply_export.hpp.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "options.hpp"
#include "ply_export.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_formats.hpp"

namespace umbra::cli {
namespace {

struct ExportOptions {
  std::string input;
  std::string output;
  bool mesh = false;
  bool color = false;
};

int run_export(const ExportOptions& options) {
  check_can_save(options.output);  // before the (maybe long) load
  const OccupancyMap map = load_any_map(options.input);
  if (options.color && !map.has_color()) {
    throw std::runtime_error(options.input + ": the map has no colors (it was built without --color); export it "
                                             "without --color");
  }
  const PlyExportSummary summary = export_ply(map, options.output, PlyExportOptions{options.mesh, options.color});
  if (options.mesh) {
    std::printf("wrote %s: %llu cubes (%llu vertices, %llu triangles), %llu bytes\n", options.output.c_str(),
                static_cast<unsigned long long>(summary.vertices / 8), static_cast<unsigned long long>(summary.vertices),
                static_cast<unsigned long long>(summary.faces), static_cast<unsigned long long>(summary.bytes));
  } else {
    std::printf("wrote %s: %llu points (occupied voxel centres), %llu bytes\n", options.output.c_str(),
                static_cast<unsigned long long>(summary.vertices), static_cast<unsigned long long>(summary.bytes));
  }
  if (summary.uncolored > 0) {
    std::fprintf(stderr, "note: %llu occupied voxels have no color sample; they are grey (%d, %d, %d)\n",
                 static_cast<unsigned long long>(summary.uncolored), kNoColor.r, kNoColor.g, kNoColor.b);
  }
  return kSuccess;
}

/// CLI11 check: the output is named .ply (any case).
CLI::Validator ply_extension() {
  return CLI::Validator(
      [](std::string& name) -> std::string {
        std::string extension = std::filesystem::path(name).extension().string();
        for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return extension == ".ply" ? "" : "'" + name + "': export writes PLY files; name the output .ply";
      },
      "FILE.ply");
}

}  // namespace

Command add_export_command(CLI::App& app) {
  auto options = std::make_shared<ExportOptions>();
  CLI::App* command = app.add_subcommand(
      "export", "Write the occupied voxels of a map as a PLY point cloud (voxel centres) or a mesh of cubes");
  command->add_option("input", options->input, "map to read (.umb, .bt, .ot)")->required()->check(map_extension());
  command->add_option("-o,--output", options->output, "PLY file to write (binary little endian); replaced atomically")
      ->required()
      ->check(ply_extension());
  command->add_flag("--mesh", options->mesh,
                    "one cube per occupied node (8 vertices, 12 triangles) instead of one point per occupied voxel");
  command->add_flag("--color", options->color,
                    "red, green, blue per vertex from the map's colors (maps built with --color; voxels without a "
                    "color are grey)");
  add_memory_option(*command);
  return [options] { return run_export(*options); };
}

}  // namespace umbra::cli
