// The exact DDA: OctoMap's voxel-by-voxel ray stepping (computeRayKeys,
// castRay), the one set of rules every exact walk in umbra follows, with an
// exact jump out of a whole node.
//
// The rules are OctoMap's to the bit: double t_max/t_delta per axis from the
// origin voxel's border (start_axis, below: the one place they are set up;
// ray/voxel_walk.hpp's brick-stepping walk for the integrators starts from
// it too), the axis with the smallest t_max steps, ties going to the later
// axis (next_axis). So the walk's events (one per voxel border crossed) come
// in the order (t value ascending, axis descending), and the t value of an
// axis's n-th border is t_max plus t_delta added n times, each addition
// rounded: the repeated sum, not t_max + n * t_delta, which can round
// differently and turn a tie the other way.
//
// ExactDda steps by integer keys, for the queries: leave_node(depth) uses the
// rules above to move the walk, in one call, to the voxel it would first
// enter outside the depth-`depth` node it is in, with the t_max values it
// would have there: per axis it only adds t_delta the number of times the
// walk would (a few predictable additions per border), instead of choosing
// an axis and looking the voxel up at every step. A segment or ray cast
// inside a node known to hold nothing blocking jumps over it and visits
// exactly the voxels the plain walk visits outside it
// (tests/ray/exact_dda_test.cpp checks this against a copy of
// computeRayKeys, on rays whose crossings tie). SegmentWalk, below, is a
// segment check's walk built on it.
//
// This file must not be compiled with floating-point contraction (FMA):
// the sums would round differently from OctoMap's.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/assert.hpp"
#include "ray/ray_direction.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra::detail {

/// How the half-voxel from the origin voxel's centre to its border is
/// rounded: computeRayKeys rounds it to float, castRay keeps it double.
enum class HalfVoxel { kFloat, kDouble };

/// The DDA along one axis at the origin voxel.
struct DdaAxis {
  int step;        // -1, 0 or +1 key per voxel border crossed
  double t_max;    // ray parameter at the next voxel border
  double t_delta;  // ray parameter per voxel
};

/// The DDA along one axis at the origin voxel (key `origin_key`, coordinate
/// `origin` on this axis), heading along the normalised float `direction`
/// component, as OctoMap sets it up: the border half a voxel from the origin
/// voxel's centre, the parameters in double. An axis the ray does not move
/// along never steps (t_max and t_delta the largest double).
inline DdaAxis start_axis(const Grid& grid, std::uint32_t origin_key, float origin, float direction,
                          HalfVoxel half_voxel) {
  DdaAxis axis;
  axis.step = direction > 0.0f ? 1 : (direction < 0.0f ? -1 : 0);
  if (axis.step == 0) {
    axis.t_max = std::numeric_limits<double>::max();
    axis.t_delta = std::numeric_limits<double>::max();
    return axis;
  }
  double border = grid.axis_center(origin_key);
  const double half = axis.step * grid.resolution() * 0.5;
  border += half_voxel == HalfVoxel::kFloat ? double(static_cast<float>(half)) : half;
  axis.t_max = (border - origin) / direction;
  axis.t_delta = grid.resolution() / std::fabs(direction);
  return axis;
}

/// The axis whose border the walk crosses next: the smallest t_max, ties
/// going to the later axis (OctoMap's choice).
inline int next_axis(const double (&t_max)[3]) {
  if (t_max[0] < t_max[1]) return t_max[0] < t_max[2] ? 0 : 2;
  return t_max[1] < t_max[2] ? 1 : 2;
}

class ExactDda {
 public:
  using HalfVoxel = detail::HalfVoxel;

  ExactDda() = default;
  /// At the voxel of `origin` (key `origin_key`), heading along the
  /// normalised float `direction`.
  ExactDda(const Grid& grid, Vec3f origin, Key origin_key, Vec3f direction, HalfVoxel half_voxel)
      : key_{origin_key.x, origin_key.y, origin_key.z},
        code_(morton::encode(origin_key)),
        limit_(grid.keys_per_axis()) {
    for (int axis = 0; axis < 3; ++axis) {
      const DdaAxis start = start_axis(grid, origin_key[axis], origin[axis], direction[axis], half_voxel);
      step_[axis] = start.step;
      t_max_[axis] = start.t_max;
      t_delta_[axis] = start.t_delta;
    }
  }

  [[nodiscard]] std::uint64_t code() const { return code_; }
  [[nodiscard]] Key key() const {
    return {static_cast<std::uint32_t>(key_[0]), static_cast<std::uint32_t>(key_[1]),
            static_cast<std::uint32_t>(key_[2])};
  }
  /// The ray parameter of the next border the walk crosses.
  [[nodiscard]] double next_border() const { return std::min(std::min(t_max_[0], t_max_[1]), t_max_[2]); }

  /// Into the next voxel; false (staying put) at the map's edge. `entered`
  /// receives the ray parameter at which the ray enters it.
  bool advance(double& entered) {
    const int dim = next_axis(t_max_);
    const std::int64_t next = key_[dim] + step_[dim];
    // A step of 0 on the chosen axis: no axis is left to move along.
    if (step_[dim] == 0 || next < 0 || next >= limit_) return false;
    entered = t_max_[dim];
    key_[dim] = next;
    t_max_[dim] += t_delta_[dim];
    code_ = step_[dim] > 0 ? morton::increment(code_, dim) : morton::decrement(code_, dim);
    return true;
  }

  /// What leave_node did.
  enum class Left {
    kOut,          // the walk is in the first voxel past the node; `entered` is where it entered it
    kBeyondLimit,  // the walk crosses no border of the node's up to ray parameter `limit`: it ends inside
    kMapEdge,      // the first voxel past the node is outside the map (the walk stays where it was)
  };

  /// As advance() repeated until the walk leaves the depth-`depth` node it
  /// is in, without visiting the voxels in between (see the file comment).
  /// A walk that stops once past `limit` (a segment's length, a cast's
  /// range) passes `limit`, and the jump costs steps up to `limit` at most.
  Left leave_node(int depth, double limit, double& entered) {
    const std::int64_t size = std::int64_t{1} << depth;
    std::int64_t exit_steps[3];  // per axis, the steps that take the walk out of the node (0: never)
    for (int axis = 0; axis < 3; ++axis) {
      const std::int64_t low = key_[axis] & ~(size - 1);
      exit_steps[axis] = step_[axis] == 0 ? 0 : (step_[axis] > 0 ? low + size - key_[axis] : key_[axis] - low + 1);
    }
    // Guess the axis that leaves first from t_max + (n - 1) * t_delta, then
    // check the guess with the exact sums: the exact sums of the other axes
    // are needed anyway, and those of a wrong guess are not (about 250
    // additions per segment check on TUM at 2 cm computed for every axis,
    // against about 100 this way).
    int guess = -1;
    double earliest = 0.0;
    for (int axis = 2; axis >= 0; --axis) {  // the later axis first: it wins ties
      if (step_[axis] == 0) continue;
      const double t = t_max_[axis] + double(exit_steps[axis] - 1) * t_delta_[axis];
      if (guess < 0 || t < earliest) {
        guess = axis;
        earliest = t;
      }
    }
    Left left = Left::kOut;
    if (leave_through(guess, exit_steps, limit, entered, left)) return left;
    // A near tie the guess got wrong.
    for (int axis = 2; axis >= 0; --axis) {
      if (axis != guess && step_[axis] != 0 && leave_through(axis, exit_steps, limit, entered, left)) return left;
    }
    UMBRA_ASSERT(false && "one axis leaves the node first");
    return Left::kBeyondLimit;
  }

 private:
  /// leave_node if `axis` is the one that leaves the node first; false
  /// (changing nothing) when another axis leaves it before.
  bool leave_through(int axis, const std::int64_t (&exit_steps)[3], double limit, double& entered, Left& left) {
    double t_exit = t_max_[axis];
    for (std::int64_t k = 1; k < exit_steps[axis] && t_exit <= limit; ++k) t_exit += t_delta_[axis];
    const bool beyond = t_exit > limit;
    // The other axes step over every border that comes before the exit in
    // the walk's order (a smaller t, or the same t on a later axis), or, when
    // the exit lies beyond the limit, every border up to the limit. Reaching
    // their own exit that way refutes `axis`.
    double t_next[3];
    std::int64_t steps[3] = {0, 0, 0};
    for (int other = 0; other < 3; ++other) {
      if (other == axis || step_[other] == 0) continue;
      double t = t_max_[other];
      std::int64_t n = 0;
      if (beyond) {
        while (n < exit_steps[other] && t <= limit) {
          t += t_delta_[other];
          ++n;
        }
      } else {
        while (n < exit_steps[other] && (t < t_exit || (t == t_exit && other > axis))) {
          t += t_delta_[other];
          ++n;
        }
      }
      if (n == exit_steps[other]) return false;
      t_next[other] = t;
      steps[other] = n;
    }
    if (beyond) {
      left = Left::kBeyondLimit;
      return true;
    }
    const std::int64_t next = key_[axis] + step_[axis] * exit_steps[axis];
    if (next < 0 || next >= limit_) {
      left = Left::kMapEdge;
      return true;
    }
    for (int other = 0; other < 3; ++other) {
      if (other == axis || step_[other] == 0) continue;
      t_max_[other] = t_next[other];
      key_[other] += step_[other] * steps[other];
    }
    key_[axis] = next;
    t_max_[axis] = t_exit + t_delta_[axis];
    code_ = morton::encode(key());
    entered = t_exit;
    left = Left::kOut;
    return true;
  }

  std::int64_t key_[3] = {};
  std::uint64_t code_ = 0;
  std::int64_t limit_ = 0;
  int step_[3] = {};
  double t_max_[3] = {};
  double t_delta_[3] = {};
};

/// The voxels a segment check looks at: those of OctoMap's
/// computeRayKeys(from, to), from the voxel of `from` up to, not including,
/// the voxel of `to`, in walk order, then the voxel of `to` itself. After
/// looking at code(), the caller says how far the walk may jump: next(d)
/// with d >= 1 when the voxel lies in a depth-d node none of whose other
/// voxels needs a look (the walk goes to the first voxel past that node; it
/// steps on voxel by voxel when the end voxel is in the node), 0 otherwise.
class SegmentWalk {
 public:
  SegmentWalk() = default;
  SegmentWalk(const Grid& grid, Vec3f from, Key from_key, Vec3f to, Key to_key)
      : end_code_(morton::encode(to_key)), code_(end_code_), at_end_(from_key == to_key) {
    if (at_end_) return;
    // Direction and length rounded as computeRayKeys rounds them (a hair-thin
    // segment whose float length underflows normalised in double: ray_direction).
    const RayDirection direction = ray_direction(from, to);
    length_ = direction.length;
    dda_ = ExactDda(grid, from, from_key, direction.unit, ExactDda::HalfVoxel::kFloat);
    code_ = dda_.code();
  }

  [[nodiscard]] std::uint64_t code() const { return code_; }
  /// Whether code() is the end voxel (the last one).
  [[nodiscard]] bool at_end() const { return at_end_; }
  /// Whether the end voxel has been passed: nothing is left to look at.
  [[nodiscard]] bool done() const { return done_; }

  void next(int jump_depth) {
    if (at_end_) {
      done_ = true;
      return;
    }
    double entered = 0.0;
    const int shift = 3 * jump_depth;
    bool going;
    if (jump_depth >= 1 && (code_ >> shift) != (end_code_ >> shift)) {
      going = dda_.leave_node(jump_depth, length_, entered) == ExactDda::Left::kOut;
    } else {
      going = dda_.advance(entered);
    }
    // computeRayKeys stops at the end voxel, or once every next border lies
    // beyond the segment's length (rounding can make it miss the end voxel).
    going = going && dda_.code() != end_code_ && dda_.next_border() <= length_;
    at_end_ = !going;
    code_ = going ? dda_.code() : end_code_;
  }

 private:
  ExactDda dda_;
  std::uint64_t end_code_ = 0;
  std::uint64_t code_ = 0;
  double length_ = 0.0;  // OctoMap's float value
  bool at_end_ = true;
  bool done_ = false;
};

}  // namespace umbra::detail
