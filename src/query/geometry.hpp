// Geometry of the query shapes against node cubes: does a cube lie outside
// a shape, partly in it, or wholly inside? Traversals use the answer to skip
// subtrees (outside), to stop testing (inside), or to look closer (partly).
//
// "Outside" must be exact: a cube reported outside has no point in the
// shape, so a subtree is never skipped wrongly. "Inside" must be sure
// (every point of the cube is in the shape). For the convex shapes a cube
// is inside iff its eight corners are. Between the two, "partly" means the
// cube does intersect the shape, so that a leaf (a voxel, or a node treated
// as a leaf at the query's depth) belongs to the shape iff it is not
// outside. Cost: a few dozen flops per test; the oriented box's separating
// axis test is the dearest (15 axes).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "umbra/core/aabb.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::detail {

enum class Overlap : unsigned char { outside, partly, inside };

/// The eight corners of a box.
inline std::array<Vec3d, 8> corners(const Aabb& box) {
  std::array<Vec3d, 8> out;
  for (unsigned i = 0; i < 8; ++i) {
    out[i] = {(i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y, (i & 4) ? box.max.z : box.min.z};
  }
  return out;
}

/// Squared distance from a point to a box (0 inside).
inline double distance_squared(Vec3d p, const Aabb& box) {
  double sum = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double below = box.min[axis] - p[axis];
    const double above = p[axis] - box.max[axis];
    const double d = below > 0.0 ? below : (above > 0.0 ? above : 0.0);
    sum += d * d;
  }
  return sum;
}

/// Squared distance from a point to the farthest point of a box.
inline double farthest_distance_squared(Vec3d p, const Aabb& box) {
  double sum = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = std::max(std::fabs(p[axis] - box.min[axis]), std::fabs(p[axis] - box.max[axis]));
    sum += d * d;
  }
  return sum;
}

inline Overlap overlap(const Aabb& shape, const Aabb& cube) {
  for (int axis = 0; axis < 3; ++axis) {
    if (cube.min[axis] > shape.max[axis] || cube.max[axis] < shape.min[axis]) return Overlap::outside;
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (cube.min[axis] < shape.min[axis] || cube.max[axis] > shape.max[axis]) return Overlap::partly;
  }
  return Overlap::inside;
}

inline Overlap overlap(const Sphere& sphere, const Aabb& cube) {
  const double r2 = sphere.radius * sphere.radius;
  if (distance_squared(sphere.center, cube) > r2) return Overlap::outside;
  return farthest_distance_squared(sphere.center, cube) <= r2 ? Overlap::inside : Overlap::partly;
}

/// Squared distance between the segment a-b and a box (0 when they meet).
double segment_box_distance_squared(Vec3d a, Vec3d b, const Aabb& box);
/// Squared distance from a point to the segment a-b.
double point_segment_distance_squared(Vec3d p, Vec3d a, Vec3d b);

inline Overlap overlap(const Capsule& capsule, const Aabb& cube) {
  const double r2 = capsule.radius * capsule.radius;
  if (segment_box_distance_squared(capsule.a, capsule.b, cube) > r2) return Overlap::outside;
  for (const Vec3d& c : corners(cube)) {
    if (point_segment_distance_squared(c, capsule.a, capsule.b) > r2) return Overlap::partly;
  }
  return Overlap::inside;
}

Overlap overlap(const OrientedBox& box, const Aabb& cube);

/// A Frustum with its frame computed once; contains() is Frustum::contains
/// to the bit (Frustum::contains calls it).
struct FrustumGeometry {
  explicit FrustumGeometry(const Frustum& frustum);
  [[nodiscard]] bool contains(Vec3d point) const;
  /// Where the points of `box` (a box of voxel centres) lie: outside when
  /// surely none is inside, inside when surely all are, else partly. Not
  /// exact near the boundary (a margin keeps it safe): callers resolve
  /// "partly" down to single points with contains().
  [[nodiscard]] Overlap overlap(const Aabb& box) const;
  /// contains(point), deciding with the side planes and the squared range
  /// where the margin allows and with contains() only near the boundary.
  [[nodiscard]] bool contains_quickly(Vec3d point) const;
  /// How many of the n^3 points (xs[i], ys[j], zs[k]) contains() accepts
  /// (n <= 8), deciding as contains_quickly() does with the terms of each
  /// coordinate computed once: a block of voxel centres at a time.
  [[nodiscard]] int count_grid_points(const double* xs, const double* ys, const double* zs, int n) const;

  Frustum frustum;
  Vec3d f, l, u;
  // Inward normals of the four side planes through the origin.
  std::array<Vec3d, 4> side;
  double cos_half_h, sin_half_h, cos_half_v, sin_half_v;
};

// Inline: the information gain asks it of every node it walks (12% of a
// fast 20 cm query's cycles as an out-of-line call).
inline Overlap FrustumGeometry::overlap(const Aabb& box) const {
  const Vec3d o = frustum.origin;
  const double nearest2 = distance_squared(o, box);
  const double farthest2 = farthest_distance_squared(o, box);
  const double range_margin = 1e-9 * (frustum.max_range + 1.0);
  const double beyond = frustum.max_range + range_margin;
  if (nearest2 > beyond * beyond) return Overlap::outside;
  // Squared distances against squared bounds, no sqrt (a sqrt per node was
  // a third of this test; the ulps squaring moves are far inside range_margin).
  const double before = frustum.min_range - range_margin;
  if (before > 0.0 && farthest2 < before * before) return Overlap::outside;
  const double within = frustum.min_range + range_margin;
  const double short_of = frustum.max_range - range_margin;
  bool all_inside = farthest2 <= short_of * short_of && nearest2 >= within * within;
  // Each side plane's value over the box: its value at the centre plus or
  // minus the half extents projected on the normal (the extremes over the
  // eight corners, in four multiplications instead of eight dot products).
  const Vec3d half = (box.max - box.min) * 0.5;
  const Vec3d centre = box.min + half - o;
  // The plane tests and the per-point atan2 test may round differently by a
  // few ulps: decide only with a margin, leave the rest to contains(). The
  // margin scales with the farthest point's distance, bounded here by the
  // sum of its coordinates' magnitudes (>= the distance).
  const double farthest_l1 = std::fabs(centre.x) + half.x + std::fabs(centre.y) + half.y + std::fabs(centre.z) + half.z;
  const double margin = 1e-9 * (farthest_l1 + 1.0);
  for (const Vec3d& normal : side) {
    const double middle = normal.dot(centre);
    const double reach = std::fabs(normal.x) * half.x + std::fabs(normal.y) * half.y + std::fabs(normal.z) * half.z;
    const double lowest = middle - reach;
    const double highest = middle + reach;
    if (highest < -margin) return Overlap::outside;
    if (lowest <= margin) all_inside = false;
  }
  return all_inside ? Overlap::inside : Overlap::partly;
}

}  // namespace umbra::detail
