// DepthPyramid: the nearest and farthest reading over any rectangle of a
// depth image, in a few reads.
//
// Level 0 is the image; every level above halves both sides (rounding up),
// a cell holding the minimum and the maximum of the (up to) four cells below
// it. A pixel without a reading counts as depth 0, so a rectangle's minimum
// is 0 when any of its pixels has no reading and its maximum is 0 when none
// has one. range() reads the cells of the level whose cells are at least
// half the rectangle's longer side: at most 3 x 3 cells, which cover the
// rectangle and a little more around it. The answer is therefore
// conservative: the minimum it gives is at most the rectangle's, the
// maximum at least, which is all the projective integrator needs to decide
// a node whole (the price of the extra margin is only a node split more
// often). The maxima of a level are also the projective rule's windows
// (projective_frame.hpp), read directly with level_max().
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace umbra {

class DepthPyramid {
 public:
  struct Range {
    float min = 0.0f;  ///< 0 when some pixel has no reading
    float max = 0.0f;  ///< 0 when no pixel has one
  };

  /// Builds the levels over an image (metres, 0: no reading), row by row:
  /// the minima from `nearest`, the maxima from `farthest` (the same image
  /// for a depth image; a scan's images keep several readings a pixel).
  /// Both must outlive the pyramid's use: level 0 reads them in place.
  void build(const float* nearest, const float* farthest, int width, int height);

  /// The range over pixels [u0, u1] x [v0, v1] (inclusive; inside the image).
  [[nodiscard]] Range range(int u0, int v0, int u1, int v1) const;
  /// The same from finer cells: those of the level whose cells are at
  /// least an eighth of the rectangle's longer side (up to 9 x 9 cells,
  /// read four at a time), so the answer reaches at most a quarter of the
  /// side beyond the rectangle instead of up to a whole side. Rectangles
  /// up to 7 pixels wide are read pixel by pixel: their range is exact.
  /// The projective walk's node test (projective_tracer.cpp), where the
  /// rectangles are the few pixels a node projects onto and a pixel of
  /// slack decides whether a node in the cone of empty pixels is skipped.
  [[nodiscard]] Range fine_range(int u0, int v0, int u1, int v1) const;

  [[nodiscard]] int levels() const { return static_cast<int>(levels_.size()); }
  /// 2^level, the pixels a cell of `level` is wide, and its inverse, both
  /// exact (powers of two). Not std::ldexp: that is a call into libm
  /// (scalbn), 0.6% of a steady TUM frame at 2 cm from whole_brick and the
  /// walk's node tests.
  [[nodiscard]] static double cell_pixels(int level) { return static_cast<double>(std::uint64_t{1} << level); }
  [[nodiscard]] static float pixel_cells(int level) { return 1.0f / static_cast<float>(std::uint64_t{1} << level); }
  [[nodiscard]] int width(int level) const { return levels_[static_cast<std::size_t>(level)].width; }
  [[nodiscard]] int height(int level) const { return levels_[static_cast<std::size_t>(level)].height; }
  /// The maxima of a level, row by row (level 0: `farthest` itself).
  [[nodiscard]] const float* level_max(int level) const { return levels_[static_cast<std::size_t>(level)].max_cells; }
  /// The 2 x 2 windows of level `level` >= 1, (width + 1) x (height + 1)
  /// of them: entry (b + 1) (width + 1) + (a + 1) is the maximum of the
  /// cells (a, a + 1) x (b, b + 1) that lie in the level, for a in [-1,
  /// width - 1] and b in [-1, height - 1]. One read instead of four for
  /// the projective rule's windows.
  [[nodiscard]] const float* window_max(int level) const {
    return levels_[static_cast<std::size_t>(level)].window.data();
  }

  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  struct Level {
    int width = 0;
    int height = 0;
    std::vector<float> min;     // level >= 1 (level 0 is the images build() was given)
    std::vector<float> max;
    const float* min_cells = nullptr;  // min's or the image's data
    const float* max_cells = nullptr;
    std::vector<float> window;  // level >= 1: see window_max()
  };
  void build_windows(Level& level);

  std::vector<Level> levels_;
  std::vector<float> pair_max_;  // build_windows' scratch, kept between images
};

namespace detail {

/// The least of `lowest` and the largest of `highest` over columns [u0, u1]
/// of rows [v0, v1] (row r starts at r * stride), folded into `least` and
/// `largest` as std::min(least, x) and std::max(largest, x) would (a NaN
/// reading is passed over either way). Four columns at a time with SSE2: a
/// TUM brick at 2 cm reads 54 cells on average, and whole_brick was a fifth
/// of a steady frame. Rows of four or more cover their last columns with an
/// overlapping load (min and max do not mind a cell read twice).
inline void rectangle_min_max(const float* lowest, const float* highest, int stride, int u0, int u1, int v0, int v1,
                              float& least, float& largest) {
  int u = u0;
#if defined(__SSE2__)
  const int n = u1 - u0 + 1;
  if (n >= 4) {
    __m128 low = _mm_set1_ps(least);
    __m128 high = _mm_set1_ps(largest);
    for (int row = v0; row <= v1; ++row) {
      const std::size_t start = static_cast<std::size_t>(row) * static_cast<std::size_t>(stride);
      const float* low_row = lowest + start;
      const float* high_row = highest + start;
      for (int column = u0;; column += 4) {
        const int at = std::min(column, u1 - 3);
        // The reading first: MINPS and MAXPS return their second operand when one is a NaN.
        low = _mm_min_ps(_mm_loadu_ps(low_row + at), low);
        high = _mm_max_ps(_mm_loadu_ps(high_row + at), high);
        if (at == u1 - 3) break;
      }
    }
    alignas(16) float lows[4];
    alignas(16) float highs[4];
    _mm_store_ps(lows, low);
    _mm_store_ps(highs, high);
    least = std::min(std::min(lows[0], lows[1]), std::min(lows[2], lows[3]));
    largest = std::max(std::max(highs[0], highs[1]), std::max(highs[2], highs[3]));
    return;
  }
#endif
  for (int row = v0; row <= v1; ++row) {
    const std::size_t start = static_cast<std::size_t>(row) * static_cast<std::size_t>(stride);
    for (int column = u; column <= u1; ++column) {
      least = std::min(least, lowest[start + static_cast<std::size_t>(column)]);
      largest = std::max(largest, highest[start + static_cast<std::size_t>(column)]);
    }
  }
}

}  // namespace detail

}  // namespace umbra
