// walk_ray: the voxels a ray passes, exactly as OctoMap's computeRayKeys.
//
// A 3D DDA (Amanatides & Woo) from the voxel of `origin` towards the voxel of
// `end`, visiting every voxel before the end voxel. To visit the same voxels
// as OctoMap, the arithmetic is OctoMap's to the bit: float direction and
// length, double tMax/tDelta, ties broken towards the later axis, and the
// stop when the travelled distance exceeds the ray length (accumulated
// rounding can make the walk miss the end voxel). That is why this file
// must not be compiled with floating-point contraction (FMA) enabled.
//
// Cost: a few double additions and compares per voxel; the Morton code is
// stepped with bit operations instead of being re-encoded.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// Length of a float vector rounded as OctoMap's Vector3::norm(): the squared
/// sum in float, the square root in double.
inline double octomap_norm(Vec3f v) {
  const float squared = v.x * v.x + v.y * v.y + v.z * v.z;
  return std::sqrt(static_cast<double>(squared));
}

namespace detail {

/// The DDA state of one ray: everything the stepping loop reads.
struct RayState {
  std::uint64_t code;      // Morton code of the current voxel
  std::uint64_t end_code;  // Morton code of the end voxel
  double length;           // ray length (OctoMap's float value)
  double t_max[3];         // ray parameter at the next voxel border, per axis
  double t_delta[3];       // ray parameter per voxel, per axis
  // Stepping the Morton code of one axis by +-1 without decoding it:
  // ((code & axis bits) | fill) + add, masked back. fill = ~axis bits and
  // add = 1 increments (the carry runs through the other axes' bits); fill = 0
  // and add = -1 decrements.
  std::uint64_t fill[3];
  std::uint64_t add[3];
  // Integer keys, tracked only for rays that may touch the map's edge.
  std::int64_t key[3];
  std::int64_t key_step[3];
  std::int64_t key_limit;
  // For jumps over whole nodes (walk_ray_skipping): where the ray starts and
  // its (float) direction, the parameter t of which t_max and length are.
  double origin[3];
  double direction[3];
};

/// Steps the ray until it reaches the end voxel or its length; visits every
/// voxel in between. kGuarded: stop at the map's edge instead of wrapping.
template <bool kGuarded, typename Visit>
void step_ray(RayState& ray, Visit& visit) {
  // Axis constants stay in registers because every index below is a constant.
  // Which axis steps is data dependent; the branches are still cheaper than
  // selects here (measured: 3.5 vs 4.2 ns per voxel).
  auto advance = [&ray]<int kAxis>() -> bool {
    constexpr std::uint64_t bits = morton::kAxisBits << kAxis;
    if constexpr (kGuarded) {
      ray.key[kAxis] += ray.key_step[kAxis];
      if (static_cast<std::uint64_t>(ray.key[kAxis]) >= static_cast<std::uint64_t>(ray.key_limit)) {
        return false;
      }
    }
    ray.code = ((((ray.code & bits) | ray.fill[kAxis]) + ray.add[kAxis]) & bits) | (ray.code & ~bits);
    ray.t_max[kAxis] += ray.t_delta[kAxis];
    return true;
  };
  for (;;) {
    bool inside;
    // OctoMap's choice: the smallest t_max, ties going to the later axis.
    if (ray.t_max[0] < ray.t_max[1]) {
      inside = ray.t_max[0] < ray.t_max[2] ? advance.template operator()<0>()
                                           : advance.template operator()<2>();
    } else {
      inside = ray.t_max[1] < ray.t_max[2] ? advance.template operator()<1>()
                                           : advance.template operator()<2>();
    }
    if (!inside || ray.code == ray.end_code) return;
    if (std::min(std::min(ray.t_max[0], ray.t_max[1]), ray.t_max[2]) > ray.length) return;
    visit(ray.code);
  }
}

}  // namespace detail

namespace detail {

/// The DDA state at the voxel of `origin`, as OctoMap's computeRayKeys sets
/// it up. Returns whether the ray may touch the map's edge (then the walk
/// must track keys: step_ray<true>).
inline bool start_ray(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key, RayState& ray) {
  ray.code = morton::encode(origin_key);
  ray.end_code = morton::encode(end_key);
  Vec3f direction = end - origin;
  const auto length = static_cast<float>(octomap_norm(direction));
  direction = {direction.x / length, direction.y / length, direction.z / length};
  ray.length = length;

  const double resolution = grid.resolution();
  ray.key_limit = grid.keys_per_axis();
  // Rounding can carry the walk at most one voxel past the box spanned by
  // the two end voxels; only rays whose box touches the map's edge need the
  // guarded loop.
  bool near_edge = false;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint32_t k0 = origin_key[axis];
    const std::uint32_t k1 = end_key[axis];
    near_edge |= std::min(k0, k1) == 0 || std::int64_t{std::max(k0, k1)} + 1 >= ray.key_limit;
    ray.key[axis] = k0;
    ray.origin[axis] = origin[axis];
    const float d = direction[axis];
    ray.direction[axis] = d;
    const int step = d > 0.0f ? 1 : (d < 0.0f ? -1 : 0);
    ray.key_step[axis] = step;
    ray.fill[axis] = step > 0 ? ~(morton::kAxisBits << axis) : 0;
    ray.add[axis] = step > 0 ? 1 : ~std::uint64_t{0};
    if (step != 0) {
      double border = grid.axis_center(k0);
      border += static_cast<float>(step * resolution * 0.5);
      ray.t_max[axis] = (border - origin[axis]) / d;
      ray.t_delta[axis] = resolution / std::fabs(d);
    } else {
      ray.t_max[axis] = std::numeric_limits<double>::max();
      ray.t_delta[axis] = std::numeric_limits<double>::max();
    }
  }
  return near_edge;
}

/// Moves the ray from the node of depth `depth` it is in to the first voxel
/// past it. Returns false when that voxel is outside the map.
inline bool jump_over_node(const Grid& grid, int depth, RayState& ray) {
  const Key low = morton::decode(morton::node_begin(ray.code, depth));
  const std::uint32_t size = 1u << depth;
  const double resolution = grid.resolution();
  const double offset = grid.key_offset();
  double t_exit = std::numeric_limits<double>::max();
  int exit_axis = 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (ray.key_step[axis] == 0) continue;
    const double border_key = ray.key_step[axis] > 0 ? double(low[axis] + size) : double(low[axis]);
    const double t = ((border_key - offset) * resolution - ray.origin[axis]) / ray.direction[axis];
    if (t <= t_exit) {
      t_exit = t;
      exit_axis = axis;
    }
  }
  Key key;
  for (int axis = 0; axis < 3; ++axis) {
    std::int64_t k;
    if (axis == exit_axis) {
      k = ray.key_step[axis] > 0 ? std::int64_t{low[axis]} + size : std::int64_t{low[axis]} - 1;
      if (k < 0 || k >= ray.key_limit) return false;
    } else {
      const double position = ray.origin[axis] + ray.direction[axis] * t_exit;
      k = static_cast<std::int64_t>(std::floor(position / resolution + offset));
      k = std::clamp<std::int64_t>(k, low[axis], std::int64_t{low[axis]} + size - 1);
    }
    key[axis] = static_cast<std::uint32_t>(k);
    ray.key[axis] = k;
    if (ray.key_step[axis] != 0) {
      const double border_key = ray.key_step[axis] > 0 ? double(k + 1) : double(k);
      ray.t_max[axis] = ((border_key - offset) * resolution - ray.origin[axis]) / ray.direction[axis];
    }
  }
  ray.code = morton::encode(key);
  return true;
}

/// step_ray, asking skip(node_code) at every depth-`depth` node the walk
/// enters whether to jump over it without visiting its voxels.
template <bool kGuarded, typename Skip, typename Visit>
void step_ray_skipping(const Grid& grid, int depth, RayState& ray, Skip& skip, Visit& visit) {
  const int shift = 3 * depth;
  std::uint64_t node = ~std::uint64_t{0};  // the node of the last visited voxel
  auto arrive = [&]() -> bool {            // at ray.code: false when the walk is over
    for (;;) {
      if (ray.code == ray.end_code) return false;
      if (std::min(std::min(ray.t_max[0], ray.t_max[1]), ray.t_max[2]) > ray.length) return false;
      if ((ray.code >> shift) == node) return true;
      node = ray.code >> shift;
      if (!skip(node << shift)) return true;
      if (!jump_over_node(grid, depth, ray)) return false;
      node = ~std::uint64_t{0};
    }
  };
  // The first voxel: as walk_ray, visited whatever the length.
  node = ray.code >> shift;
  if (skip(node << shift)) {
    if (!jump_over_node(grid, depth, ray)) return;
    node = ~std::uint64_t{0};
    if (!arrive()) return;
  }
  visit(ray.code);
  auto advance = [&ray]<int kAxis>() -> bool {
    constexpr std::uint64_t bits = morton::kAxisBits << kAxis;
    if constexpr (kGuarded) {
      ray.key[kAxis] += ray.key_step[kAxis];
      if (static_cast<std::uint64_t>(ray.key[kAxis]) >= static_cast<std::uint64_t>(ray.key_limit)) {
        return false;
      }
    }
    ray.code = ((((ray.code & bits) | ray.fill[kAxis]) + ray.add[kAxis]) & bits) | (ray.code & ~bits);
    ray.t_max[kAxis] += ray.t_delta[kAxis];
    return true;
  };
  for (;;) {
    bool inside;
    if (ray.t_max[0] < ray.t_max[1]) {
      inside = ray.t_max[0] < ray.t_max[2] ? advance.template operator()<0>()
                                           : advance.template operator()<2>();
    } else {
      inside = ray.t_max[1] < ray.t_max[2] ? advance.template operator()<1>()
                                           : advance.template operator()<2>();
    }
    if (!inside || !arrive()) return;
    visit(ray.code);
  }
}

}  // namespace detail

/// Calls visit(code) for each voxel from the voxel of `origin` up to, not
/// including, the voxel of `end`; `origin_key` and `end_key` are their keys
/// (grid.key_checked of each, computed once by callers that trace many rays).
template <typename Visit>
void walk_ray(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Visit&& visit) {
  if (origin_key == end_key) return;
  detail::RayState ray;
  const bool near_edge = detail::start_ray(grid, origin, origin_key, end, end_key, ray);
  visit(ray.code);
  if (near_edge) {
    detail::step_ray<true>(ray, visit);
  } else {
    detail::step_ray<false>(ray, visit);
  }
}

/// walk_ray, except that at every depth-`depth` node the walk enters (the
/// one it starts in too) it calls skip(code of the node's first voxel):
/// when that returns true the walk jumps to the first voxel past the node,
/// visiting none of the node's voxels. When skip never returns true it
/// visits exactly walk_ray's voxels; after a jump its rounding is its own
/// (the fast integrator, which uses it, has no OctoMap counterpart).
template <typename Skip, typename Visit>
void walk_ray_skipping(const Grid& grid, int depth, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Skip&& skip,
                       Visit&& visit) {
  if (origin_key == end_key) return;
  detail::RayState ray;
  detail::start_ray(grid, origin, origin_key, end, end_key, ray);
  // Jumps can land anywhere in the map: always track keys.
  detail::step_ray_skipping<true>(grid, depth, ray, skip, visit);
}

/// Calls visit(code) for each voxel from the voxel of `origin` up to, not
/// including, the voxel of `end`. Returns false (visiting nothing) when
/// either end lies outside the map.
template <typename Visit>
bool walk_ray(const Grid& grid, Vec3f origin, Vec3f end, Visit&& visit) {
  const std::optional<Key> origin_key = grid.key_checked(origin);
  const std::optional<Key> end_key = grid.key_checked(end);
  if (!origin_key || !end_key) return false;
  walk_ray(grid, origin, *origin_key, end, *end_key, visit);
  return true;
}

}  // namespace umbra
