// Shapes that queries take: regions to iterate, check for collision or look
// into. Coordinates in metres, angles in radians.
//
// When does a node belong to a shape (docs/design.md, Semantics)?
//  - Aabb, Sphere, OrientedBox, Capsule: when its cube (closed) intersects
//    the shape; for a sphere, when the squared distance from the centre to
//    the cube is at most r^2; for a capsule, when the distance from its
//    segment to the cube is at most its radius.
//  - Segment: when it holds a voxel of the segment's ray walk, the voxels
//    OctoMap's computeRayKeys(from, to) visits plus the voxel of `to` (so a
//    line check answers what a ray cast in OctoMap would see).
//  - Frustum: when the centre of one of its finest voxels is inside the
//    frustum (the information gain counts voxels by their centres).
// Each shape's validate() throws std::invalid_argument naming the bad value;
// every query calls it.
#pragma once

#include <array>

#include "umbra/core/aabb.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

struct Sphere {
  Vec3d center;
  double radius = 0.0;  ///< >= 0
  void validate() const;
};

/// A line segment; in collision checks, its ray walk (see the file comment).
struct Segment {
  Vec3d from;
  Vec3d to;
  void validate() const;
};

/// The points within `radius` of the segment from `a` to `b`.
struct Capsule {
  Vec3d a;
  Vec3d b;
  double radius = 0.0;  ///< >= 0
  void validate() const;
};

/// A box turned in space: centre, half edge lengths along its own axes, and
/// those axes (orthonormal) in map coordinates.
struct OrientedBox {
  Vec3d center;
  Vec3d half_extents;                       ///< >= 0 on each axis
  std::array<Vec3d, 3> axes{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

  /// Axes from angles, as a Frustum looks: x along f = (cos p cos y,
  /// cos p sin y, sin p) (positive pitch looks up), y along l = (-sin y,
  /// cos y, 0) and z along f x l, then y and z turned by `roll` about x.
  static OrientedBox from_yaw_pitch_roll(Vec3d center, Vec3d half_extents, double yaw, double pitch, double roll);
  /// Axes of the rotation given by a unit quaternion (w, x, y, z); normalised first.
  static OrientedBox from_quaternion(Vec3d center, Vec3d half_extents, double w, double x, double y, double z);
  void validate() const;
};

/// A sensor's field of view (docs/design.md, Semantics): seen from `origin` looking along
/// f = (cos p cos y, cos p sin y, sin p) with left l = (-sin y, cos y, 0) and
/// up u = f x l, a point c with d = c - origin is inside iff d.f > 0,
/// |atan2(d.l, d.f)| <= hfov/2, |atan2(d.u, d.f)| <= vfov/2 and
/// min_range <= |d| <= max_range.
struct Frustum {
  Vec3d origin;
  double yaw = 0.0;
  double pitch = 0.0;
  double hfov = 0.0;       ///< full horizontal field of view, in (0, pi)
  double vfov = 0.0;       ///< full vertical field of view, in (0, pi)
  double min_range = 0.0;  ///< >= 0
  double max_range = 0.0;  ///< > min_range

  /// Angles given in degrees (as the command line takes them).
  static Frustum from_degrees(Vec3d origin, double yaw_deg, double pitch_deg, double hfov_deg, double vfov_deg,
                              double min_range, double max_range);
  [[nodiscard]] Vec3d forward() const;
  [[nodiscard]] Vec3d left() const;
  [[nodiscard]] Vec3d up() const;
  /// The membership test above, for one point.
  [[nodiscard]] bool contains(Vec3d point) const;
  void validate() const;
};

}  // namespace umbra
