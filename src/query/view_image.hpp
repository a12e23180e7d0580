// ViewImage: the obstacles in a sensor's field of view as a pinhole image,
// so that the information gain can decide whole nodes, and most single
// rays, without walking rays through the tree.
//
// Seen from the apex o (the rays' float origin) looking along f, a point p
// with d = p - o and d.f > 0 falls on the image plane at (x, y) = (d.l, d.u)
// / d.f. The image covers the frustum's field of view, |x| <= tan(hfov/2),
// |y| <= tan(vfov/2), plus a border, in square pixels of `pixel` image
// units. Central projection maps segments to segments, so the directions of
// all points of a box lie in the rectangle spanned by its corners'
// projections (its footprint); a box reaching behind the plane d.f = near
// is clipped there first.
//
// Every obstacle (occupied voxel or solid occupied node, grown by the ray
// walk's rounding margin) is drawn into the pixels of its footprint:
//   nearest(p):    distance from o to the nearest obstacle drawn into p. A
//                  ray through p meets no obstacle before that distance.
//   candidates(p): the `kCandidates` nearest of them, to test a single ray
//                  against exactly, and whether more were drawn (overflow).
// Pyramids of minima and of maxima over 2x2 blocks answer "nearest obstacle
// anywhere in this footprint" and "is there an obstacle before d in every
// pixel of it" with at most four reads each.
//
// Layout: row-major float arrays, level 0 is the image; candidates are
// kCandidates slots per pixel, sorted by distance, plus a count byte.
// Cost: drawing is O(pixels of the footprint) per obstacle; reset() reuses
// the arrays of the previous pose (one image per thread).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "core/assert.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra::detail {

struct PixelRect {
  int x0, y0, x1, y1;  // inclusive
};

class ViewImage {
 public:
  static constexpr int kCandidates = 6;
  static constexpr std::uint8_t kOverflow = 0x80;  // in count: an obstacle was dropped

  struct Candidate {
    float near;           // distance from the apex to the obstacle (grown), rounded down
    std::uint32_t index;  // the caller's obstacle number
  };

  struct Setup {
    Vec3d apex;
    Vec3d f, l, u;           // view frame (unit, orthogonal)
    double half_width;       // tan(hfov / 2) plus the border, image units
    double half_height;      // tan(vfov / 2) plus the border
    double pixel;            // pixel edge, image units
    double near_plane;       // boxes are clipped at d.f = near_plane (> 0)
    bool candidates;         // keep candidate lists (else only the nearest distances)
    bool maxima = true;      // build the pyramid of maxima (nearest_in_every_pixel)
  };

  /// Starts an empty image (nothing drawn: nearest is +infinity everywhere).
  void reset(const Setup& setup);

  [[nodiscard]] const Setup& setup() const { return setup_; }
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }

  /// The footprint of `box`: the pixels holding the directions of its points
  /// with d.f >= near_plane, clamped to the image. False when there is no
  /// such point or the footprint misses the image. `clipped` tells whether
  /// part of the box lies before the near plane.
  bool footprint(const Aabb& box, PixelRect& rect, bool& clipped) const;
  /// The pixel of one direction d (d.f > 0); false outside the image.
  /// (Inline: called per ray, and a Vec3d passed by value to an out-of-line
  /// call was copied through the stack, a store-forwarding stall per ray.)
  bool pixel_of(const Vec3d& d, int& x, int& y) const {
    const Setup& s = setup_;
    const double z = d.dot(s.f);
    if (!(z >= s.near_plane)) return false;
    // One division: the reciprocal of z, and of the pixel (set in reset()).
    const double inverse = 1.0 / z;
    const double fx = (d.dot(s.l) * inverse + s.half_width) * inverse_pixel_;
    const double fy = (d.dot(s.u) * inverse + s.half_height) * inverse_pixel_;
    if (!(fx >= 0.0 && fx < double(width_) && fy >= 0.0 && fy < double(height_))) return false;
    x = static_cast<int>(fx);
    y = static_cast<int>(fy);
    return true;
  }

  /// Draws an obstacle at distance `near` into the pixels of `rect`.
  void draw(const PixelRect& rect, double near, std::uint32_t index);
  /// Builds the pyramids; call after the last draw().
  void finish();

  /// The least nearest-obstacle distance over the pixels of `rect` (a lower
  /// bound: the pyramid may read a few pixels more).
  [[nodiscard]] float nearest(const PixelRect& rect) const { return read(minima_, rect, false); }
  /// The greatest nearest-obstacle distance over the pixels of `rect` (an
  /// upper bound, for the same reason).
  [[nodiscard]] float nearest_in_every_pixel(const PixelRect& rect) const {
    UMBRA_ASSERT(setup_.maxima);
    return read(maxima_, rect, true);
  }
  [[nodiscard]] float nearest(int x, int y) const { return minima_[0][index(x, y)]; }
  /// The candidates of a pixel, nearest first; `overflow` when more
  /// obstacles were drawn there (always, when the image keeps no lists).
  [[nodiscard]] const Candidate* candidates(int x, int y, int& count, bool& overflow) const {
    if (!setup_.candidates) {
      count = 0;
      overflow = true;
      return nullptr;
    }
    const std::uint8_t c = counts_[index(x, y)];
    count = c & ~kOverflow;
    overflow = (c & kOverflow) != 0;
    return &candidates_[index(x, y) * kCandidates];
  }

 private:
  [[nodiscard]] std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width_) + std::size_t(x); }
  using Pyramid = std::vector<std::vector<float>>;  // level 0 is the image, then 2x2 blocks, 4x4, ...
  [[nodiscard]] float read(const Pyramid& pyramid, const PixelRect& rect, bool greatest) const;
  void build(Pyramid& pyramid, bool greatest);

  Setup setup_{};
  double inverse_pixel_ = 1.0;
  int width_ = 0;
  int height_ = 0;
  Pyramid minima_;  // nearest obstacle per pixel, then minima of blocks
  Pyramid maxima_;  // the same pixels, then maxima of blocks
  std::vector<std::array<int, 2>> level_sizes_;  // width, height per level
  std::unique_ptr<Candidate[]> candidates_;  // kCandidates per pixel
  std::size_t candidate_capacity_ = 0;
  std::vector<std::uint8_t> counts_;
};

}  // namespace umbra::detail
