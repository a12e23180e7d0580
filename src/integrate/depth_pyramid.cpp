#include "integrate/depth_pyramid.hpp"

#include <algorithm>
#include <bit>
#include <limits>

#include "core/assert.hpp"

namespace umbra {

void DepthPyramid::build(const float* nearest, const float* farthest, int width, int height) {
  UMBRA_ASSERT(width >= 1 && height >= 1);
  std::size_t count = 1;
  for (int w = width, h = height; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++count;
  levels_.resize(count);
  Level& base = levels_[0];
  base.width = width;
  base.height = height;
  // Level 0 is the images themselves (not copied).
  base.min_cells = nearest;
  base.max_cells = farthest;
  for (std::size_t l = 1; l < count; ++l) {
    const Level& below = levels_[l - 1];
    Level& level = levels_[l];
    level.width = (below.width + 1) / 2;
    level.height = (below.height + 1) / 2;
    const std::size_t cells = std::size_t(level.width) * std::size_t(level.height);
    level.min.resize(cells);
    level.max.resize(cells);
    level.min_cells = level.min.data();
    level.max_cells = level.max.data();
    for (int y = 0; y < level.height; ++y) {
      const std::size_t row0 = std::size_t(2 * y) * below.width;
      const std::size_t row1 = std::size_t(std::min(2 * y + 1, below.height - 1)) * below.width;
      for (int x = 0; x < level.width; ++x) {
        const std::size_t x0 = std::size_t(2 * x);
        const std::size_t x1 = std::size_t(std::min(2 * x + 1, below.width - 1));
        const std::size_t cell = std::size_t(y) * level.width + x;
        level.min[cell] = std::min(std::min(below.min_cells[row0 + x0], below.min_cells[row0 + x1]),
                                   std::min(below.min_cells[row1 + x0], below.min_cells[row1 + x1]));
        level.max[cell] = std::max(std::max(below.max_cells[row0 + x0], below.max_cells[row0 + x1]),
                                   std::max(below.max_cells[row1 + x0], below.max_cells[row1 + x1]));
      }
    }
  }
  // Level 0's windows are not read (a voxel smaller than two pixels reads its own).
  for (std::size_t l = 1; l < count; ++l) build_windows(levels_[l]);
}

void DepthPyramid::build_windows(Level& level) {
  // The 2 x 2 windows, from a = -1 and b = -1 on: each the maximum of a row
  // pair's two column maxima, the padding cells reading 0.
  const int wide = level.width + 1;
  level.window.resize(std::size_t(wide) * std::size_t(level.height + 1));
  std::vector<float>& pair_max = pair_max_;  // column maxima of rows b, b + 1; 0 at both ends
  pair_max.assign(std::size_t(level.width) + 2, 0.0f);
  for (int b = -1; b < level.height; ++b) {
    const float* upper = b >= 0 ? level.max_cells + std::size_t(b) * level.width : nullptr;
    const float* lower = b + 1 < level.height ? level.max_cells + std::size_t(b + 1) * level.width : nullptr;
    for (int x = 0; x < level.width; ++x) {
      pair_max[std::size_t(x) + 1] = std::max(upper ? upper[x] : 0.0f, lower ? lower[x] : 0.0f);
    }
    float* out = level.window.data() + std::size_t(b + 1) * wide;
    for (int a = -1; a < level.width; ++a) {
      out[a + 1] = std::max(pair_max[std::size_t(a) + 1], pair_max[std::size_t(a) + 2]);
    }
  }
}

DepthPyramid::Range DepthPyramid::range(int u0, int v0, int u1, int v1) const {
  UMBRA_ASSERT(u0 >= 0 && v0 >= 0 && u0 <= u1 && v0 <= v1 && u1 < levels_[0].width && v1 < levels_[0].height);
  const unsigned extent = static_cast<unsigned>(std::max(u1 - u0, v1 - v0) + 1);
  // Cells of 2^l >= extent / 2 pixels: the rectangle meets at most 3 per axis.
  const int l = std::min(static_cast<int>(std::bit_width(extent)) - 1, static_cast<int>(levels_.size()) - 1);
  const Level& level = levels_[static_cast<std::size_t>(l)];
  const int x0 = u0 >> l;
  const int x1 = u1 >> l;
  const int y0 = v0 >> l;
  const int y1 = v1 >> l;
  Range result{level.min_cells[std::size_t(y0) * level.width + x0], 0.0f};
  for (int y = y0; y <= y1; ++y) {
    const std::size_t row = std::size_t(y) * level.width;
    for (int x = x0; x <= x1; ++x) {
      result.min = std::min(result.min, level.min_cells[row + x]);
      result.max = std::max(result.max, level.max_cells[row + x]);
    }
  }
  return result;
}

DepthPyramid::Range DepthPyramid::fine_range(int u0, int v0, int u1, int v1) const {
  UMBRA_ASSERT(u0 >= 0 && v0 >= 0 && u0 <= u1 && v0 <= v1 && u1 < levels_[0].width && v1 < levels_[0].height);
  const unsigned extent = static_cast<unsigned>(std::max(u1 - u0, v1 - v0) + 1);
  // Cells of 2^l in (extent / 8, extent / 4] pixels: at most 9 per axis.
  const int l = std::clamp(static_cast<int>(std::bit_width(extent)) - 3, 0, static_cast<int>(levels_.size()) - 1);
  const Level& level = levels_[static_cast<std::size_t>(l)];
  Range result{std::numeric_limits<float>::infinity(), 0.0f};
  detail::rectangle_min_max(level.min_cells, level.max_cells, level.width, u0 >> l, u1 >> l, v0 >> l, v1 >> l,
                            result.min, result.max);
  return result;
}

std::size_t DepthPyramid::memory_bytes() const {
  std::size_t bytes = levels_.capacity() * sizeof(Level);
  for (const Level& level : levels_) {
    bytes += (level.min.capacity() + level.max.capacity() + level.window.capacity()) * sizeof(float);
  }
  return bytes;
}

}  // namespace umbra
