// How OctoMap rounds a ray before walking it: its length (octomap_norm),
// its normalised float direction (ray_direction) and its end point's key
// (key_of_rounded). Every exact walk (ray/exact_dda.hpp, ray/voxel_walk.hpp)
// and every caller that must agree with them on a ray's length uses these.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// Length of a float vector rounded as OctoMap's Vector3::norm(): the squared
/// sum in float, the square root in double.
inline double octomap_norm(Vec3f v) {
  const float squared = v.x * v.x + v.y * v.y + v.z * v.z;
  return std::sqrt(static_cast<double>(squared));
}

/// octomap_norm(v) > bound (bound >= 0), the square root taken only near
/// the bound: sqrt is correctly rounded and monotonic, so a squared sum well
/// below (above) bound^2 decides it (the square root's latency was a third
/// of the projective integrator's hits on the TUM frames at 2 cm).
inline bool octomap_norm_exceeds(Vec3f v, double bound) {
  const double squared = static_cast<double>(v.x * v.x + v.y * v.y + v.z * v.z);
  const double limit = bound * bound;
  if (squared < limit * (1.0 - 1e-9)) return false;
  if (squared > limit * (1.0 + 1e-9)) return true;
  return octomap_norm(v) > bound;
}

/// A ray's normalised direction and its length, as OctoMap's computeRayKeys
/// computes them: the float offset, octomap_norm rounded to float, a float
/// division per component.
struct RayDirection {
  Vec3f unit;
  float length;
};

/// The direction and length from `from` to `to` (two points in the map)
/// that the ray walks use. OctoMap's arithmetic, except where it breaks:
/// when every component of the offset is below about 2.6e-23 m (the points
/// straddle the voxel border at coordinate 0 from a hair's breadth, e.g.
/// (-1e-23, 1e-23, 0) from the origin) the float squared length underflows
/// to 0, and OctoMap's division by it makes the direction infinite or NaN:
/// its walk never reaches the end voxel and runs until its key buffer
/// overflows (liboctomap 1.9.7 crashes). Here such a ray is normalised in
/// double instead, and walks as OctoMap's arithmetic would with a direction
/// that did not underflow. Its length is then at most 5e-23 m, far below
/// the rounding of the voxel borders, so in practice it visits the origin's
/// voxel and stops (docs/octomap-agreement.md).
inline RayDirection ray_direction(Vec3f from, Vec3f to) {
  const Vec3f offset = to - from;
  const auto length = static_cast<float>(octomap_norm(offset));
  if (length > 0.0f) return {{offset.x / length, offset.y / length, offset.z / length}, length};
  const Vec3d exact = Vec3d(to) - Vec3d(from);
  const double norm = exact.norm();
  if (!(norm > 0.0)) return {{0.0f, 0.0f, 0.0f}, 0.0f};  // the same point: no direction
  return {Vec3f(exact / norm), static_cast<float>(norm)};
}

/// The finest key of a ray's end that a caller gave in double and the walk
/// uses rounded to float (`rounded`), as OctoMap's rays are; throws
/// std::out_of_range naming `what` and saying so, since the float value
/// (-3276.800048828125 for -3276.8) can lie outside the map when the given
/// one does not.
inline Key key_of_rounded(const Grid& grid, Vec3f rounded, const char* what) {
  try {
    return grid.key(Vec3d(rounded));
  } catch (const std::out_of_range& e) {
    throw std::out_of_range(std::string(what) + ", rounded to float as OctoMap's rays are: " + e.what());
  }
}

}  // namespace umbra
