// Image: an 8-bit RGB picture in memory, and its PNG file form (libpng).
//
// write_png never leaves a half-written file under the real name: it writes
// a temporary file in the same folder, flushes it to disk and renames it over
// the target (an atomic replace on POSIX file systems). read_png reads any
// PNG libpng understands and converts it to 8-bit RGB (grey is expanded,
// 16-bit samples are reduced, an alpha channel is composited onto black);
// files written by write_png read back exactly. Both throw
// std::runtime_error naming the file and the reason, and
// std::invalid_argument for an inconsistent Image.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "umbra/core/color.hpp"

namespace umbra {

struct Image {
  int width = 0;
  int height = 0;
  /// Row-major, 3 bytes (r, g, b) per pixel, width * height * 3 bytes. For a
  /// map picture row 0 is the northern edge (largest y) and column 0 the
  /// western edge (smallest x).
  std::vector<std::uint8_t> rgb;

  // Where a map picture lies in the map frame (set by render_topdown; zero
  // for other images and not stored in the PNG file): pixel (column, row)
  // covers x in left_x + [column, column + 1) * metres_per_pixel and
  // y in top_y - [row + 1, row) * metres_per_pixel.
  double metres_per_pixel = 0.0;
  double left_x = 0.0;
  double top_y = 0.0;
  int depth = 0;  ///< map depth one pixel stands for (0 = one finest voxel column)

  Image() = default;
  /// A width x height picture filled with `fill`; throws std::invalid_argument
  /// unless both sides are > 0.
  Image(int width_pixels, int height_pixels, Rgb fill = {});

  /// Color of a pixel; throws std::out_of_range outside the picture.
  [[nodiscard]] Rgb at(int column, int row) const;
  /// Sets a pixel; throws std::out_of_range outside the picture.
  void set(int column, int row, Rgb color);

  /// Throws std::invalid_argument unless width and height are > 0 and rgb
  /// holds exactly width * height * 3 bytes.
  void validate() const;
};

/// Writes `image` as an 8-bit RGB PNG file (see the top of this file).
void write_png(const Image& image, const std::filesystem::path& path);

/// Reads a PNG file into an 8-bit RGB image (metres_per_pixel etc. are 0).
/// Throws MemoryLimitError when its pixels (3 bytes each) exceed memory_limit().
Image read_png(const std::filesystem::path& path);

}  // namespace umbra
