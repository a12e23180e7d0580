// How a node meets a box of finest keys: the test the tree's region walks
// (decay in a region, forgetting outside a moving window) share.
#pragma once

#include <cstdint>
#include <optional>

#include "tree/occupancy_tree.hpp"

namespace umbra::detail {

enum class Overlap { outside, partial, inside };

/// How the depth-`depth` node whose first voxel is `code` meets `box`.
inline Overlap overlap(std::uint64_t code, int depth, const OccupancyTree::KeyBox& box) {
  const Key corner = morton::decode(code);
  const std::uint64_t last = (std::uint64_t{1} << depth) - 1;
  bool inside = true;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint64_t begin = corner[axis];
    const std::uint64_t end = begin + last;
    if (end < box.lo[axis] || begin > box.hi[axis]) return Overlap::outside;
    inside &= begin >= box.lo[axis] && end <= box.hi[axis];
  }
  return inside ? Overlap::inside : Overlap::partial;
}

/// The same for an optional region: no region covers everything.
inline Overlap overlap(std::uint64_t code, int depth, const std::optional<OccupancyTree::KeyBox>& region) {
  return region ? overlap(code, depth, *region) : Overlap::inside;
}

}  // namespace umbra::detail
