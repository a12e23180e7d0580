// A top-down picture of a map: one pixel per vertical column of voxels.
//
// render_topdown looks straight down the z axis (x to the right, y up, north
// at the top) over the bounds of the map's known space plus a small margin.
// A column with an occupied voxel gets the color of its highest occupied
// voxel's height on a ramp (height_ramp below); a column with free voxels
// only is light grey; a column with nothing known is dark. An optional height
// window (min_z, max_z) ignores everything outside it, e.g. to cut away the
// ceiling of a building. When a picture at one pixel per finest voxel would
// be wider or taller than max_pixels_per_side, one pixel stands for a coarser
// node instead (the picture says which in Image::depth and metres_per_pixel);
// such a pixel is occupied if any voxel under it is, else free if any is.
//
// Cost model: two passes over the map's leaves (for_each_leaf: bounds, then
// painting) plus one pass over the pixels; a leaf costs one visit plus the
// pixels it covers, so large pruned free nodes are cheap and nothing is
// queried voxel by voxel. Memory: 4 bytes per pixel while painting, then the
// 3-byte-per-pixel picture.
#pragma once

#include <optional>

#include "umbra/io/png_writer.hpp"
#include "umbra/core/color.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

struct TopdownOptions {
  /// Largest picture side in pixels, margin included; 2 * margin_pixels + 1 .. 65536.
  int max_pixels_per_side = 4096;
  /// Unknown-colored border around the known space, in pixels (>= 0).
  int margin_pixels = 2;
  /// Height window: only voxels whose centre z lies in [min_z, max_z] count.
  std::optional<double> min_z;
  std::optional<double> max_z;
  /// Heights at the two ends of the color ramp; by default the lowest and
  /// the highest column top in the picture.
  std::optional<double> ramp_low_z;
  std::optional<double> ramp_high_z;
  Rgb free_color{200, 200, 200};
  Rgb unknown_color{32, 32, 40};

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// The height ramp: t in [0, 1] (clamped; NaN counts as 0) is interpolated
/// linearly between five colors, low to high: blue (48, 64, 200), cyan
/// (0, 170, 210), green (60, 180, 75), yellow (240, 200, 40) and red
/// (215, 48, 39), at t = 0, 0.25, 0.5, 0.75 and 1; channels are rounded to the
/// nearest integer. None of them is grey, so heights never look like free or
/// unknown space. A column's t is (z - low) / (high - low) with z the centre
/// height of its highest occupied voxel, or 0 when high <= low.
Rgb height_ramp(double t);

/// Renders the picture described at the top of this file. Throws
/// std::invalid_argument for bad options, and for a map with no known voxel
/// (inside the height window): there is nothing to frame, and a picture of
/// nothing is more likely a caller's mistake than a wish.
Image render_topdown(const OccupancyMap& map, const TopdownOptions& options = {});

}  // namespace umbra
