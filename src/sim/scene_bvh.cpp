#include "scene_bvh.hpp"

#include <cmath>
#include <cstdlib>

namespace umbra::sim::detail {

namespace {

BvhBox merged(const BvhBox& a, const BvhBox& b) {
  return {{std::min(a.min.x, b.min.x), std::min(a.min.y, b.min.y), std::min(a.min.z, b.min.z)},
          {std::max(a.max.x, b.max.x), std::max(a.max.y, b.max.y), std::max(a.max.z, b.max.z)}};
}

/// Half the surface area: what the chance of a random ray meeting a box grows with.
double half_area(const BvhBox& box) {
  const Vec3d e = box.max - box.min;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

}  // namespace

void SceneBvh::insert(const BvhBox& bounds, std::uint32_t primitive) {
  const auto leaf = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({bounds, kNone, {kNone, kNone}, primitive, 0});
  if (root_ == kNone) {
    root_ = leaf;
    return;
  }

  // Descend while going into a child is cheaper than making the new leaf
  // the sibling of the whole subtree here (surface-area cost: a new parent
  // costs the merged area; every ancestor grows by the same increase).
  std::uint32_t sibling = root_;
  while (!nodes_[sibling].is_leaf()) {
    const Node& node = nodes_[sibling];
    const double grown = half_area(merged(node.box, bounds));
    const double here = 2.0 * grown;
    const double inherited = 2.0 * (grown - half_area(node.box));
    std::array<double, 2> below{};
    for (int c = 0; c < 2; ++c) {
      const Node& child = nodes_[node.child[c]];
      const double child_grown = half_area(merged(child.box, bounds));
      below[c] = inherited + (child.is_leaf() ? child_grown : child_grown - half_area(child.box));
    }
    if (here <= below[0] && here <= below[1]) break;
    sibling = node.child[below[0] <= below[1] ? 0 : 1];
  }

  const auto parent = static_cast<std::uint32_t>(nodes_.size());
  const std::uint32_t old_parent = nodes_[sibling].parent;
  nodes_.push_back({merged(nodes_[sibling].box, bounds), old_parent, {sibling, leaf}, kNone,
                    nodes_[sibling].height + 1});
  nodes_[sibling].parent = parent;
  nodes_[leaf].parent = parent;
  if (old_parent == kNone) {
    root_ = parent;
  } else {
    replace_child(old_parent, sibling, parent);
  }

  for (std::uint32_t index = parent; index != kNone; index = nodes_[index].parent) {
    index = balance(index);
    refit(index);
  }
}

void SceneBvh::refit(std::uint32_t index) {
  Node& node = nodes_[index];
  const Node& a = nodes_[node.child[0]];
  const Node& b = nodes_[node.child[1]];
  node.box = merged(a.box, b.box);
  node.height = 1 + std::max(a.height, b.height);
}

void SceneBvh::replace_child(std::uint32_t parent, std::uint32_t old_child, std::uint32_t new_child) {
  Node& node = nodes_[parent];
  node.child[node.child[0] == old_child ? 0 : 1] = new_child;
}

std::uint32_t SceneBvh::balance(std::uint32_t index) {
  Node& top = nodes_[index];
  if (top.is_leaf() || top.height < 2) return index;
  const int difference = nodes_[top.child[1]].height - nodes_[top.child[0]].height;
  if (std::abs(difference) <= 1) return index;

  // top{short, tall{taller, shorter}} becomes tall{top{short, shorter}, taller}:
  // the same leaves, one level less on the tall side.
  const int tall_slot = difference > 0 ? 1 : 0;
  const std::uint32_t tall = top.child[tall_slot];
  Node& up = nodes_[tall];
  const int taller_slot = nodes_[up.child[0]].height >= nodes_[up.child[1]].height ? 0 : 1;
  const std::uint32_t taller = up.child[taller_slot];
  const std::uint32_t shorter = up.child[1 - taller_slot];

  up.parent = top.parent;
  if (top.parent == kNone) {
    root_ = tall;
  } else {
    replace_child(top.parent, index, tall);
  }
  up.child = {index, taller};
  top.parent = tall;
  top.child[tall_slot] = shorter;
  nodes_[shorter].parent = index;
  refit(index);
  refit(tall);
  return tall;
}

}  // namespace umbra::sim::detail
