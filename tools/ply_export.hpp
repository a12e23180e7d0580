// The occupied voxels of a map as a PLY file (`umbra export`), what
// OctoMap's octree2pointcloud and bt2vrml give, in the format other tools
// load (MeshLab, CloudCompare, Blender, Open3D, PCL).
//
// Points: one vertex per occupied finest voxel, at its centre (a pruned
// occupied node gives one per voxel it covers), as float x y z. Mesh: one
// cube per occupied childless node (a pruned node is one larger cube): 8
// vertices and 12 triangles wound counter-clockwise seen from outside
// ("property list uchar int vertex_indices"). With colors, every vertex
// carries uchar red, green, blue: the voxel's color, or kNoColor grey for
// an occupied voxel that received no color sample. Binary little endian
// ("format binary_little_endian 1.0"), whatever the machine.
//
// The file is built in memory (15 bytes a point with color, 276 bytes a
// cube), so its size is checked against the memory limit first
// (umbra/core/memory_limit.hpp), then written atomically like every file
// umbra saves (umbra/io/file_saving.hpp). Cost: two passes over the
// childless nodes (count, then write).
#pragma once

#include <cstdint>
#include <filesystem>

#include "umbra/core/color.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::cli {

/// The color of an occupied voxel without one, in a colored export.
inline constexpr Rgb kNoColor{128, 128, 128};

struct PlyExportOptions {
  bool mesh = false;   ///< cubes instead of points
  bool color = false;  ///< red, green, blue per vertex (the map must have color)
};

struct PlyExportSummary {
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;       ///< triangles (mesh only)
  std::uint64_t uncolored = 0;  ///< occupied voxels given kNoColor
  std::uint64_t bytes = 0;       ///< the file's size
};

/// Writes the occupied voxels of `map` to `path`. Throws
/// std::invalid_argument when `color` is asked of a map without color,
/// MemoryLimitError (naming `path`, the need and the limit) when the file
/// would need more than the memory limit, std::runtime_error when it cannot
/// be written.
PlyExportSummary export_ply(const OccupancyMap& map, const std::filesystem::path& path,
                            const PlyExportOptions& options);

}  // namespace umbra::cli
