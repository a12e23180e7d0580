// SceneBvh: a bounding volume hierarchy over the bounds of a scene's
// primitives, so that a ray cast or a distance query visits a few of
// thousands of primitives instead of all of them.
//
// A binary tree of axis-aligned boxes, built as primitives are added (a scene
// has no "finished" moment, and its queries are const and shared between
// threads, so the tree is always complete rather than built lazily): a new
// leaf descends from the root towards the child whose box grows least in
// surface area, becomes the sibling of the node where descending stops
// paying, and the boxes on the way back up are refitted; where the two
// subtrees of a node differ in height by more than one, the taller child is
// rotated up (a single AVL rotation), which keeps the tree shallow whatever
// the order of insertion (tests/sim checks its height). Layout: nodes in one
// vector, children by index; a leaf holds a number the scene gives its
// primitive (scene.cpp: its kind and its index in that kind's list). Cost: insert
// O(height); a query visits the nodes whose boxes meet its ray (up to the
// nearest hit so far) or ball (up to the nearest distance so far), nearer
// child first.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "umbra/core/vec3.hpp"

namespace umbra::sim::detail {

struct BvhBox {
  Vec3d min;
  Vec3d max;
};

/// Parameter interval [enter, exit] of a ray inside a box, intersected with
/// [0, t_max]; empty (enter > exit) when it misses. `inverse` is 1 / d per
/// axis (+-infinity for a zero component).
inline void ray_box_interval(const BvhBox& box, Vec3d origin, Vec3d direction, Vec3d inverse, double t_max,
                             double& enter, double& exit) {
  enter = 0.0;
  exit = t_max;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0) {
      if (origin[axis] < box.min[axis] || origin[axis] > box.max[axis]) {
        enter = 1.0;
        exit = 0.0;
        return;
      }
      continue;
    }
    double low = (box.min[axis] - origin[axis]) * inverse[axis];
    double high = (box.max[axis] - origin[axis]) * inverse[axis];
    if (low > high) std::swap(low, high);
    enter = std::max(enter, low);
    exit = std::min(exit, high);
  }
}

/// Squared distance from a point to a box (0 inside).
inline double squared_distance(const BvhBox& box, Vec3d point) {
  double sum = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double outside = std::max({box.min[axis] - point[axis], 0.0, point[axis] - box.max[axis]});
    sum += outside * outside;
  }
  return sum;
}

class SceneBvh {
 public:
  /// Adds the primitive with index `primitive` and bounds `bounds`.
  void insert(const BvhBox& bounds, std::uint32_t primitive);

  [[nodiscard]] bool empty() const { return root_ == kNone; }
  /// The box around everything; only when not empty.
  [[nodiscard]] const BvhBox& bounds() const { return nodes_[root_].box; }
  /// Height of the tree (a single leaf: 0), for tests.
  [[nodiscard]] int height() const { return empty() ? -1 : nodes_[root_].height; }

  /// Calls hit(primitive, t_max) for every primitive whose bounds the ray
  /// origin + t direction meets for t in [0, t_max], nearer boxes first;
  /// hit returns the new t_max (the nearest hit so far), which prunes the
  /// rest of the walk.
  template <typename Hit>
  void cast(Vec3d origin, Vec3d direction, double t_max, Hit&& hit) const {
    if (empty()) return;
    const Ray ray{origin, direction, {1.0 / direction.x, 1.0 / direction.y, 1.0 / direction.z}};
    double enter = 0.0;
    double exit = 0.0;
    ray_box_interval(nodes_[root_].box, ray.origin, ray.direction, ray.inverse, t_max, enter, exit);
    if (enter <= exit) cast_from(root_, ray, t_max, hit);
  }

  /// Calls near(primitive, limit) for every primitive whose bounds lie
  /// within sqrt(limit_squared) of `point`, nearer boxes first; near returns
  /// the new squared limit, which prunes the rest of the walk.
  template <typename Near>
  void visit_near(Vec3d point, double limit_squared, Near&& near) const {
    if (empty()) return;
    if (squared_distance(nodes_[root_].box, point) <= limit_squared) near_from(root_, point, limit_squared, near);
  }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  struct Node {
    BvhBox box;
    std::uint32_t parent = kNone;
    std::array<std::uint32_t, 2> child{kNone, kNone};  ///< kNone for a leaf
    std::uint32_t primitive = kNone;                   ///< leaves only
    int height = 0;                                    ///< leaf 0
    [[nodiscard]] bool is_leaf() const { return child[0] == kNone; }
  };

  struct Ray {
    Vec3d origin;
    Vec3d direction;
    Vec3d inverse;  ///< 1 / direction per axis (+-infinity for 0)
  };

  // The walks recurse (depth: the tree's height) into the nearer child
  // first, and into the farther one only if it is still within the limit.
  template <typename Hit>
  void cast_from(std::uint32_t index, const Ray& ray, double& t_max, Hit& hit) const {
    const Node& node = nodes_[index];
    if (node.is_leaf()) {
      t_max = hit(node.primitive, t_max);
      return;
    }
    std::array<double, 2> enter{};
    std::array<double, 2> exit{};
    for (int c = 0; c < 2; ++c) {
      ray_box_interval(nodes_[node.child[c]].box, ray.origin, ray.direction, ray.inverse, t_max, enter[c], exit[c]);
    }
    const int first = enter[0] <= enter[1] ? 0 : 1;
    for (const int c : {first, 1 - first}) {
      if (enter[c] <= exit[c] && enter[c] <= t_max) cast_from(node.child[c], ray, t_max, hit);
    }
  }

  template <typename Near>
  void near_from(std::uint32_t index, Vec3d point, double& limit_squared, Near& near) const {
    const Node& node = nodes_[index];
    if (node.is_leaf()) {
      limit_squared = near(node.primitive, limit_squared);
      return;
    }
    const std::array<double, 2> distance{squared_distance(nodes_[node.child[0]].box, point),
                                         squared_distance(nodes_[node.child[1]].box, point)};
    const int first = distance[0] <= distance[1] ? 0 : 1;
    for (const int c : {first, 1 - first}) {
      if (distance[c] <= limit_squared) near_from(node.child[c], point, limit_squared, near);
    }
  }

  /// Refits `index`'s box and height from its children.
  void refit(std::uint32_t index);
  /// Rotates the taller child of `index` up when the heights differ by more
  /// than one; returns the node now in `index`'s place.
  std::uint32_t balance(std::uint32_t index);
  void replace_child(std::uint32_t parent, std::uint32_t old_child, std::uint32_t new_child);

  std::vector<Node> nodes_;
  std::uint32_t root_ = kNone;
};

}  // namespace umbra::sim::detail
