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

#include <cstddef>
#include <cstdint>
#include <vector>

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

}  // namespace umbra
