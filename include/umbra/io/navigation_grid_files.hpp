// A navigation grid (umbra/query/navigation_grid.hpp) as map_server's files:
// a PGM picture and the YAML file that describes it, which ROS's
// map_server and Nav2's map_server load as a static map.
//
//   umbra::save_navigation_grid(grid, "map.pgm");   // writes map.pgm and map.yaml
//
// The picture is binary PGM (P5), 8 bits per pixel, one pixel per cell,
// its first row the grid's highest y (north up, as map_saver writes it):
// free cells 254, occupied 0, unknown 205. The YAML file says
//   image: "map.pgm"          (the picture's file name; map_server reads it beside the YAML)
//   mode: trinary
//   resolution: 0.05          (metres per cell)
//   origin: [x, y, 0.0]       (the lower-left corner of the picture; yaw 0)
//   negate: 0
//   occupied_thresh: 0.65
//   free_thresh: 0.196
// map_server turns a pixel p into the occupancy (255 - p) / 255 and
// compares it with the thresholds: 254 is free, 0 occupied, 205 (0.196...,
// just above free_thresh) unknown: the grid reads back cell for cell.
// These are map_saver's own values, so maps saved by either look alike.
//
// Both files are written atomically (umbra/io/file_saving.hpp), the
// picture first: the YAML never names a picture that is not complete.
// Cost: one byte per cell, written once.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "umbra/query/navigation_grid.hpp"

namespace umbra {

/// The picture's pixel values (map_saver's).
inline constexpr std::uint8_t kPgmFree = 254;
inline constexpr std::uint8_t kPgmOccupied = 0;
inline constexpr std::uint8_t kPgmUnknown = 205;

/// The PGM file's bytes. Throws std::invalid_argument for an empty grid or
/// one whose cell count is not width * height.
[[nodiscard]] std::vector<std::uint8_t> navigation_grid_pgm(const NavigationGrid& grid);

/// The YAML file's text, naming `image_name` as the picture.
[[nodiscard]] std::string navigation_grid_yaml(const NavigationGrid& grid, const std::string& image_name);

/// Where the YAML file of a picture goes: the same path with `.yaml` for
/// `.pgm`. Throws std::invalid_argument unless `image_path` ends in .pgm.
[[nodiscard]] std::filesystem::path navigation_grid_yaml_path(const std::filesystem::path& image_path);

/// Writes `image_path` (.pgm) and the YAML file beside it; returns the YAML
/// file's path. Throws std::invalid_argument for an empty grid or a path not
/// ending in .pgm, std::runtime_error naming the file and the reason when
/// a file cannot be written (neither is then changed, or only the picture).
std::filesystem::path save_navigation_grid(const NavigationGrid& grid, const std::filesystem::path& image_path);

}  // namespace umbra
