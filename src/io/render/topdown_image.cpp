#include "umbra/io/topdown_image.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace umbra {

namespace {

// Cell values while painting: a voxel z key (>= 0) of the highest occupied
// voxel, or one of these.
constexpr std::int32_t kUnknownCell = -2;
constexpr std::int32_t kFreeCell = -1;

std::string text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

[[noreturn]] void bad_option(const char* field, const std::string& requirement, double value) {
  std::ostringstream out;
  out << "TopdownOptions::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

/// Finest z key range [low, high] of the voxels whose centre lies in the
/// height window (empty when low > high).
struct KeyRange {
  std::int64_t low;
  std::int64_t high;
};

KeyRange height_window(const Grid& grid, const TopdownOptions& options) {
  const auto keys = std::int64_t(grid.keys_per_axis());
  const auto offset = double(grid.key_offset());
  KeyRange range{0, keys - 1};
  // Voxel k's centre is (k - offset + 0.5) * resolution; clamp in double
  // before converting so that far-away limits cannot overflow.
  if (options.min_z) {
    const double k = std::ceil(*options.min_z / grid.resolution() - 0.5) + offset;
    range.low = std::int64_t(std::clamp(k, 0.0, double(keys)));
  }
  if (options.max_z) {
    const double k = std::floor(*options.max_z / grid.resolution() - 0.5) + offset;
    range.high = std::int64_t(std::clamp(k, -1.0, double(keys - 1)));
  }
  return range;
}

struct ColumnBounds {
  std::int64_t min_x = std::numeric_limits<std::int64_t>::max();
  std::int64_t min_y = std::numeric_limits<std::int64_t>::max();
  std::int64_t max_x = -1;
  std::int64_t max_y = -1;
  [[nodiscard]] bool empty() const { return max_x < 0; }
};

std::uint8_t mix(std::uint8_t a, std::uint8_t b, double f) {
  return static_cast<std::uint8_t>(std::lround(double(a) + (double(b) - double(a)) * f));
}

}  // namespace

void TopdownOptions::validate() const {
  if (margin_pixels < 0) bad_option("margin_pixels", ">= 0", margin_pixels);
  if (max_pixels_per_side < 2 * std::int64_t(margin_pixels) + 1 || max_pixels_per_side > 65536) {
    bad_option("max_pixels_per_side",
               "in [2 * margin_pixels + 1, 65536] = [" +
                   std::to_string(2 * std::int64_t(margin_pixels) + 1) + ", 65536]",
               max_pixels_per_side);
  }
  if (min_z && !std::isfinite(*min_z)) bad_option("min_z", "finite", *min_z);
  if (max_z && !std::isfinite(*max_z)) bad_option("max_z", "finite", *max_z);
  if (min_z && max_z && *min_z > *max_z) {
    bad_option("max_z", ">= min_z (" + text(*min_z) + ")", *max_z);
  }
  if (ramp_low_z && !std::isfinite(*ramp_low_z)) bad_option("ramp_low_z", "finite", *ramp_low_z);
  if (ramp_high_z && !std::isfinite(*ramp_high_z)) {
    bad_option("ramp_high_z", "finite", *ramp_high_z);
  }
  if (ramp_low_z && ramp_high_z && !(*ramp_low_z < *ramp_high_z)) {
    bad_option("ramp_high_z", "> ramp_low_z (" + text(*ramp_low_z) + ")", *ramp_high_z);
  }
}

Rgb height_ramp(double t) {
  static constexpr std::array<Rgb, 5> stops{{
      {48, 64, 200},   // blue
      {0, 170, 210},   // cyan
      {60, 180, 75},   // green
      {240, 200, 40},  // yellow
      {215, 48, 39},   // red
  }};
  if (!(t > 0.0)) return stops.front();  // also NaN
  if (t >= 1.0) return stops.back();
  const double scaled = t * double(stops.size() - 1);
  const auto index = static_cast<std::size_t>(scaled);
  const double f = scaled - double(index);
  const Rgb a = stops[index];
  const Rgb b = stops[index + 1];
  return {mix(a.r, b.r, f), mix(a.g, b.g, f), mix(a.b, b.b, f)};
}

Image render_topdown(const OccupancyMap& map, const TopdownOptions& options) {
  options.validate();
  const Grid& grid = map.grid();
  const KeyRange window = height_window(grid, options);

  // A leaf counts if it is known and overlaps the height window; returns its
  // finest-key edge length, or 0 when it does not count.
  auto counted_size = [&window](const Node& leaf) -> std::int64_t {
    if (leaf.state == OccupancyState::unknown) return 0;
    const std::int64_t size = std::int64_t{1} << leaf.depth;
    const std::int64_t z = leaf.key.z;
    if (z + size - 1 < window.low || z > window.high) return 0;
    return size;
  };

  // Pass 1: the columns holding known space.
  ColumnBounds bounds;
  map.for_each_leaf([&](const Node& leaf) {
    const std::int64_t size = counted_size(leaf);
    if (size == 0) return;
    bounds.min_x = std::min<std::int64_t>(bounds.min_x, leaf.key.x);
    bounds.min_y = std::min<std::int64_t>(bounds.min_y, leaf.key.y);
    bounds.max_x = std::max<std::int64_t>(bounds.max_x, leaf.key.x + size - 1);
    bounds.max_y = std::max<std::int64_t>(bounds.max_y, leaf.key.y + size - 1);
  });
  if (bounds.empty()) {
    std::string where;
    if (options.min_z || options.max_z) {
      std::ostringstream out;
      out << " with its centre in z [" << (options.min_z ? *options.min_z : -grid.half_extent())
          << ", " << (options.max_z ? *options.max_z : grid.half_extent()) << "]";
      where = out.str();
    }
    throw std::invalid_argument("render_topdown: the map has no known voxel" + where +
                                ", so there is nothing to draw");
  }

  // The finest depth at which the picture fits; the root depth always does
  // (one node, plus the margins, which validate() allows).
  const std::int64_t margin = options.margin_pixels;
  int depth = 0;
  auto pixels_across = [&](std::int64_t low, std::int64_t high, int d) {
    return (high >> d) - (low >> d) + 1 + 2 * margin;
  };
  while (pixels_across(bounds.min_x, bounds.max_x, depth) > options.max_pixels_per_side ||
         pixels_across(bounds.min_y, bounds.max_y, depth) > options.max_pixels_per_side) {
    ++depth;
  }
  const auto width = static_cast<int>(pixels_across(bounds.min_x, bounds.max_x, depth));
  const auto height = static_cast<int>(pixels_across(bounds.min_y, bounds.max_y, depth));
  const std::int64_t west_node =
      bounds.min_x >> depth;  // node x index of the first non-margin column
  const std::int64_t north_node =
      bounds.max_y >> depth;  // node y index of the first non-margin row

  // Pass 2: paint each counted leaf into the pixels it covers.
  std::vector<std::int32_t> cells(std::size_t(width) * std::size_t(height), kUnknownCell);
  map.for_each_leaf([&](const Node& leaf) {
    const std::int64_t size = counted_size(leaf);
    if (size == 0) return;
    const std::int64_t column_begin = (std::int64_t(leaf.key.x) >> depth) - west_node + margin;
    const std::int64_t column_end = ((leaf.key.x + size - 1) >> depth) - west_node + margin;
    const std::int64_t row_begin = north_node - ((leaf.key.y + size - 1) >> depth) + margin;
    const std::int64_t row_end = north_node - (std::int64_t(leaf.key.y) >> depth) + margin;
    const bool occupied = leaf.state == OccupancyState::occupied;
    const auto top = static_cast<std::int32_t>(std::min(leaf.key.z + size - 1, window.high));
    for (std::int64_t row = row_begin; row <= row_end; ++row) {
      std::int32_t* cell = cells.data() + row * width + column_begin;
      for (std::int64_t column = column_begin; column <= column_end; ++column, ++cell) {
        if (occupied) {
          *cell = std::max(*cell, top);
        } else if (*cell == kUnknownCell) {
          *cell = kFreeCell;
        }
      }
    }
  });

  // The ramp's ends: given, or the lowest and highest column tops.
  double ramp_low = 0.0;
  double ramp_high = 0.0;
  {
    std::int32_t lowest = std::numeric_limits<std::int32_t>::max();
    std::int32_t highest = -1;
    for (const std::int32_t cell : cells) {
      if (cell < 0) continue;
      lowest = std::min(lowest, cell);
      highest = std::max(highest, cell);
    }
    if (highest >= 0) {
      ramp_low = grid.axis_center(std::uint32_t(lowest));
      ramp_high = grid.axis_center(std::uint32_t(highest));
    }
    if (options.ramp_low_z) ramp_low = *options.ramp_low_z;
    if (options.ramp_high_z) ramp_high = *options.ramp_high_z;
  }

  Image image(width, height, options.unknown_color);
  std::uint8_t* out = image.rgb.data();
  for (const std::int32_t cell : cells) {
    Rgb color = options.unknown_color;
    if (cell == kFreeCell) {
      color = options.free_color;
    } else if (cell >= 0) {
      const double z = grid.axis_center(std::uint32_t(cell));
      color = height_ramp(ramp_high > ramp_low ? (z - ramp_low) / (ramp_high - ramp_low) : 0.0);
    }
    out[0] = color.r;
    out[1] = color.g;
    out[2] = color.b;
    out += 3;
  }

  const double node_keys = double(std::int64_t{1} << depth);
  const double offset = double(grid.key_offset());
  image.depth = depth;
  image.metres_per_pixel = grid.node_size(depth);
  image.left_x = (double(west_node - margin) * node_keys - offset) * grid.resolution();
  image.top_y = (double(north_node + 1 + margin) * node_keys - offset) * grid.resolution();
  return image;
}

}  // namespace umbra
