// walk_ray: the voxels a ray passes, exactly as OctoMap's computeRayKeys,
// stepped through Morton codes brick by brick for the integrators.
//
// The exact DDA of ray/exact_dda.hpp (its start_axis sets the walk up, and
// the loop below chooses axes by its next_axis rule, unrolled per axis) from
// the voxel of `origin` towards the voxel of `end`, visiting every voxel
// before the end voxel: float direction and length (ray/ray_direction.hpp),
// double tMax/tDelta, ties broken towards the later axis, and the stop when
// the travelled distance exceeds the ray length (accumulated rounding can
// make the walk miss the end voxel). What differs from ExactDda is only how
// the current voxel is kept: as a brick code and an index (below) instead of
// a key, the form the update batch takes, with few operations per voxel.
// This file must not be compiled with floating-point contraction (FMA).
//
// walk_ray_skipping is the fast integrator's walk: the same, but at every
// coarse node it enters it may jump over the whole node.
//
// Data layout of the walk: a voxel's Morton code is split into its brick
// (the code with the low 6 bits cleared: a 4x4x4 block of voxels, the unit of
// the update batch) and its index in the brick (the low 6 bits). A step
// moves the index with small masks; only one step in four on an axis leaves
// the brick and steps the brick's 64-bit code. Callers receive either every
// voxel's code in order (walk_ray with a visitor) or runs: a brick and the
// mask of the voxels visited in it (walk_ray_runs). A visitor that returns
// bool stops the walk by returning false (a visibility check ends at the
// first occupied voxel); one that returns nothing sees the whole walk.
//
// Cost: a few double additions and compares per voxel, about 20
// instructions (the TUM frames at 2 cm, callgrind).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "ray/exact_dda.hpp"
#include "ray/ray_direction.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

namespace detail {

inline constexpr std::uint64_t kBrickMask = 63;  // the index bits of a code

/// A ray's DDA: its constants and its state at the current voxel.
struct RayState {
  std::uint64_t brick;        // code of the current voxel's brick (low 6 bits clear)
  unsigned index;             // the current voxel's index in its brick (its code's low 6 bits)
  std::uint64_t end_brick;    // the end voxel, the same way
  unsigned end_index;
  double length;              // ray length (OctoMap's float value)
  double t_max[3];            // ray parameter at the next voxel border, per axis
  double t_delta[3];          // ray parameter per voxel, per axis
  // Stepping one axis of a Morton code by +-1 without decoding it:
  // ((code & axis bits) | fill) + add, masked back. fill = ~axis bits and
  // add = 1 increments (the carry runs through the other axes' bits); fill = 0
  // and add = -1 decrements. Index (low 6 bits) and brick (the rest) separately.
  unsigned index_fill[3];
  unsigned index_add[3];
  unsigned index_wrap[3];     // the axis's index bits before a step that leaves the brick
  std::uint64_t brick_fill[3];
  std::uint64_t brick_add[3];
  // Integer keys, tracked only for rays that may touch the map's edge.
  std::int64_t key[3];
  std::int64_t key_step[3];
  std::int64_t key_limit;
  // For jumps over whole nodes (walk_ray_skipping): where the ray starts and
  // its (float) direction; t_max and length are in this parameter.
  double origin[3];
  double direction[3];
  double inverse_direction[3];  // 1 / direction (infinite along an axis the ray does not move on)

  [[nodiscard]] std::uint64_t code() const { return brick | index; }
  void set_code(std::uint64_t code) {
    brick = code & ~kBrickMask;
    index = static_cast<unsigned>(code & kBrickMask);
  }
};

/// The DDA state at the voxel of `origin`, as OctoMap's computeRayKeys sets
/// it up. Returns whether the ray may touch the map's edge (then the walk
/// must track keys: kGuarded).
inline bool start_ray(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key, RayState& ray) {
  ray.set_code(morton::encode(origin_key));
  const std::uint64_t end_code = morton::encode(end_key);
  ray.end_brick = end_code & ~kBrickMask;
  ray.end_index = static_cast<unsigned>(end_code & kBrickMask);
  const RayDirection ray_direction = umbra::ray_direction(origin, end);
  const Vec3f direction = ray_direction.unit;
  ray.length = ray_direction.length;

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
    ray.inverse_direction[axis] = 1.0 / double(d);
    const DdaAxis dda = start_axis(grid, k0, origin[axis], d, HalfVoxel::kFloat);
    const int step = dda.step;
    ray.key_step[axis] = step;
    const unsigned index_bits = 9u << axis;  // bits axis and axis + 3
    const std::uint64_t brick_bits = (morton::kAxisBits << axis) & ~kBrickMask;
    ray.index_fill[axis] = step > 0 ? ~index_bits : 0u;
    ray.index_add[axis] = step > 0 ? 1u : ~0u;
    ray.index_wrap[axis] = step > 0 ? index_bits : 0u;
    ray.brick_fill[axis] = step > 0 ? ~brick_bits : 0;
    ray.brick_add[axis] = step > 0 ? 1 : ~std::uint64_t{0} << 6;  // -64: the brick bits are above bit 5
    ray.t_max[axis] = dda.t_max;
    ray.t_delta[axis] = dda.t_delta;
  }
  return near_edge;
}

/// Moves the ray out of the depth-`depth` node it is in and on over every
/// further node skip(node's first code) says to skip, node by node (a
/// coarse DDA: a few operations per node), to the first voxel of the first
/// node not skipped. Returns false when the walk is over before: beyond the
/// ray's length or outside the map.
template <typename Skip>
bool skip_nodes(const Grid& grid, int depth, RayState& ray, Skip& skip) {
  const double resolution = grid.resolution();
  const double offset = grid.key_offset();
  const std::int64_t node_limit = ray.key_limit >> depth;
  std::uint64_t node_code = morton::node_begin(ray.code(), depth);
  const Key first = morton::decode(node_code);
  std::int64_t node[3] = {first.x >> depth, first.y >> depth, first.z >> depth};
  // The node's far face per axis, as a ray parameter.
  double t_face[3];
  for (int axis = 0; axis < 3; ++axis) {
    if (ray.key_step[axis] == 0) {
      t_face[axis] = std::numeric_limits<double>::max();
      continue;
    }
    const std::int64_t border = (node[axis] + (ray.key_step[axis] > 0 ? 1 : 0)) << depth;
    t_face[axis] = ((double(border) - offset) * resolution - ray.origin[axis]) * ray.inverse_direction[axis];
  }
  const double node_size = resolution * double(std::int64_t{1} << depth);
  for (;;) {
    const int axis = t_face[0] < t_face[1] ? (t_face[0] < t_face[2] ? 0 : 2) : (t_face[1] < t_face[2] ? 1 : 2);
    const double t_exit = t_face[axis];
    if (t_exit > ray.length) return false;
    node[axis] += ray.key_step[axis];
    if (node[axis] < 0 || node[axis] >= node_limit) return false;
    const std::uint64_t high = (morton::kAxisBits << axis) & ~((std::uint64_t{1} << (3 * depth)) - 1);
    node_code = ray.key_step[axis] > 0 ? ((((node_code & high) | ~high) + 1) & high) | (node_code & ~high)
                                       : (((node_code & high) - 1) & high) | (node_code & ~high);
    t_face[axis] += node_size * std::fabs(ray.inverse_direction[axis]);
    if (skip(node_code)) continue;
    // Land on the ray's first voxel in this node.
    Key key;
    for (int a = 0; a < 3; ++a) {
      const std::int64_t low = node[a] << depth;
      std::int64_t k;
      if (a == axis) {
        k = ray.key_step[a] > 0 ? low : low + (std::int64_t{1} << depth) - 1;
      } else {
        const double position = (ray.origin[a] + ray.direction[a] * t_exit) / resolution + offset;
        k = static_cast<std::int64_t>(position);  // truncation is floor: position > 0 in the map
        k = std::clamp<std::int64_t>(k, low, low + (std::int64_t{1} << depth) - 1);
      }
      key[a] = static_cast<std::uint32_t>(k);
      ray.key[a] = k;
      if (ray.key_step[a] != 0) {
        const double border_key = ray.key_step[a] > 0 ? double(k + 1) : double(k);
        ray.t_max[a] = ((border_key - offset) * resolution - ray.origin[a]) * ray.inverse_direction[a];
      }
    }
    ray.set_code(morton::encode(key));
    return true;
  }
}

/// The walk's inner loop. From the current voxel (not visited yet) it visits
/// voxels through sink.voxel(brick, index) (false: stop the walk there) and, whenever the walk leaves a
/// brick and at its end, sink.leave(brick). With kSkipping, at every
/// depth-`depth` node the walk enters (the first one too) skip(node's first
/// code) may make it jump over the node. kGuarded: track keys and stop at
/// the map's edge instead of wrapping.
template <bool kGuarded, bool kSkipping, typename Sink, typename Skip>
void step_ray(const Grid& grid, int depth, RayState& ray, Sink& sink, Skip& skip) {
  const int shift = 3 * depth;
  // At the current voxel, in a node the walk was not in: jumps over skipped
  // nodes. False when the walk is over (the end voxel, the ray's length or
  // the map's edge).
  auto walk_is_over = [&]() {
    return (ray.index == ray.end_index && ray.brick == ray.end_brick) ||
           std::min(std::min(ray.t_max[0], ray.t_max[1]), ray.t_max[2]) > ray.length;
  };
  auto enter = [&]() -> bool {
    if (walk_is_over()) return false;
    if (!skip(morton::node_begin(ray.code(), depth))) return true;
    return skip_nodes(grid, depth, ray, skip) && !walk_is_over();
  };
  // The first voxel: as OctoMap, visited whatever the length.
  if constexpr (kSkipping) {
    if (skip(morton::node_begin(ray.code(), depth))) {
      if (!skip_nodes(grid, depth, ray, skip) || walk_is_over()) return;
    }
  }
  // The state lives in locals, so that it stays in registers (the sink's
  // stores could alias a struct's integers and force reloads).
  const std::uint64_t end_brick = ray.end_brick;
  const unsigned end_index = ray.end_index;
  const double length = ray.length;
  const double t_delta[3] = {ray.t_delta[0], ray.t_delta[1], ray.t_delta[2]};
  const unsigned index_fill[3] = {ray.index_fill[0], ray.index_fill[1], ray.index_fill[2]};
  const unsigned index_add[3] = {ray.index_add[0], ray.index_add[1], ray.index_add[2]};
  const unsigned index_wrap[3] = {ray.index_wrap[0], ray.index_wrap[1], ray.index_wrap[2]};
  const std::uint64_t brick_fill[3] = {ray.brick_fill[0], ray.brick_fill[1], ray.brick_fill[2]};
  const std::uint64_t brick_add[3] = {ray.brick_add[0], ray.brick_add[1], ray.brick_add[2]};
  const std::int64_t key_step[3] = {ray.key_step[0], ray.key_step[1], ray.key_step[2]};
  const std::uint64_t key_limit = static_cast<std::uint64_t>(ray.key_limit);
  for (;;) {  // once per node the walk crosses voxel by voxel (once in all without kSkipping)
    std::uint64_t brick = ray.brick;
    unsigned index = ray.index;
    double t_max[3] = {ray.t_max[0], ray.t_max[1], ray.t_max[2]};
    std::int64_t key[3] = {ray.key[0], ray.key[1], ray.key[2]};
    const std::uint64_t node = (brick | index) >> shift;
    bool left_node = false;
    if (!sink.voxel(brick, index)) return;
    // One step on axis kAxis; false when the walk is over (the map's edge, the
    // end voxel, the length) or, with kSkipping, enters a new node.
    auto advance = [&]<int kAxis>() -> bool {
      if constexpr (kGuarded) {
        key[kAxis] += key_step[kAxis];
        if (static_cast<std::uint64_t>(key[kAxis]) >= key_limit) return false;
      }
      constexpr unsigned bits = 9u << kAxis;
      const bool leaves_brick = (index & bits) == index_wrap[kAxis];
      index = ((((index & bits) | index_fill[kAxis]) + index_add[kAxis]) & bits) | (index & ~bits);
      t_max[kAxis] += t_delta[kAxis];
      if (leaves_brick) {
        constexpr std::uint64_t high = (morton::kAxisBits << kAxis) & ~kBrickMask;
        sink.leave(brick);
        brick = ((((brick & high) | brick_fill[kAxis]) + brick_add[kAxis]) & high) | (brick & ~high);
        if constexpr (kSkipping) {
          if (((brick | index) >> shift) != node) {
            left_node = true;
            return false;
          }
        }
      }
      if constexpr (kSkipping) {
        if (shift < 6 && ((brick | index) >> shift) != node) {
          sink.leave(brick);
          left_node = true;
          return false;
        }
      }
      if (index == end_index && brick == end_brick) return false;
      // OctoMap's early stop: every next border beyond the length. The other
      // two were at least the old t_max[kAxis], so only when this one passes
      // the length can all three have.
      return t_max[kAxis] <= length ||
             std::min(t_max[(kAxis + 1) % 3], t_max[(kAxis + 2) % 3]) <= length;
    };
    for (;;) {
      // next_axis (ray/exact_dda.hpp), unrolled so that each axis's step is
      // its own template instance: the smallest t_max, ties to the later axis.
      bool going;
      if (t_max[0] < t_max[1]) {
        going = t_max[0] < t_max[2] ? advance.template operator()<0>() : advance.template operator()<2>();
      } else {
        going = t_max[1] < t_max[2] ? advance.template operator()<1>() : advance.template operator()<2>();
      }
      if (!going) break;
      if (!sink.voxel(brick, index)) return;
    }
    if (!left_node) {
      sink.leave(brick);
      return;
    }
    ray.brick = brick;
    ray.index = index;
    for (int axis = 0; axis < 3; ++axis) {
      ray.t_max[axis] = t_max[axis];
      ray.key[axis] = key[axis];
    }
    if (!enter()) return;
  }
}

/// A sink that hands every voxel's code to visit(code), in walk order; a
/// visitor returning bool stops the walk with false.
template <typename Visit>
struct VoxelSink {
  Visit& visit;
  bool voxel(std::uint64_t brick, unsigned index) {
    if constexpr (std::is_same_v<decltype(visit(brick | index)), bool>) {
      return visit(brick | index);
    } else {
      visit(brick | index);
      return true;
    }
  }
  void leave(std::uint64_t) {}
};

/// A sink that hands each brick's visited voxels to run(brick, mask) as it
/// leaves it (bit i of mask: the voxel with index i).
template <typename Run>
struct RunSink {
  Run& run;
  std::uint64_t mask = 0;
  bool voxel(std::uint64_t, unsigned index) {
    mask |= std::uint64_t{1} << index;
    return true;
  }
  void leave(std::uint64_t brick) {
    if (mask != 0) run(brick, mask);
    mask = 0;
  }
};

inline constexpr auto kSkipNothing = [](std::uint64_t) { return false; };

template <bool kSkipping, typename Sink, typename Skip>
void walk(const Grid& grid, int depth, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Sink& sink,
          Skip& skip) {
  if (origin_key == end_key) return;
  RayState ray;
  if (start_ray(grid, origin, origin_key, end, end_key, ray)) {
    step_ray<true, kSkipping>(grid, depth, ray, sink, skip);
  } else {
    step_ray<false, kSkipping>(grid, depth, ray, sink, skip);
  }
}

}  // namespace detail

/// Calls visit(code) for each voxel from the voxel of `origin` up to, not
/// including, the voxel of `end` (or until visit returns false, if it returns
/// bool); `origin_key` and `end_key` are their keys
/// (grid.key_checked of each, computed once by callers that trace many rays).
template <typename Visit>
void walk_ray(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Visit&& visit) {
  detail::VoxelSink<Visit> sink{visit};
  auto skip = detail::kSkipNothing;
  detail::walk<false>(grid, 0, origin, origin_key, end, end_key, sink, skip);
}

/// walk_ray's voxels as runs: run(brick, mask) for each stretch of the walk
/// through one brick (4x4x4 voxels: brick is the first voxel's code, bit i
/// of mask the voxel brick + i). A brick the walk returns to gets another run.
template <typename Run>
void walk_ray_runs(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Run&& run) {
  detail::RunSink<Run> sink{run};
  auto skip = detail::kSkipNothing;
  detail::walk<false>(grid, 0, origin, origin_key, end, end_key, sink, skip);
}

/// walk_ray_runs, except that at every depth-`depth` node (>= 1) the walk
/// enters (the one it starts in too) it calls skip(code of the node's first
/// voxel): when that returns true the walk jumps to the first voxel past the
/// node, visiting none of the node's voxels. When skip never returns true it
/// visits exactly walk_ray's voxels; after a jump its rounding is its own
/// (the fast integrator, which uses it, has no OctoMap counterpart).
template <typename Skip, typename Run>
void walk_ray_skipping(const Grid& grid, int depth, Vec3f origin, Key origin_key, Vec3f end, Key end_key, Skip&& skip,
                       Run&& run) {
  detail::RunSink<Run> sink{run};
  detail::walk<true>(grid, depth, origin, origin_key, end, end_key, sink, skip);
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
