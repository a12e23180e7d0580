// Node: one node of a map as every query reports it, and node counts.
//
// A node at depth d covers 2^d x 2^d x 2^d finest voxels (depth 0 is a
// voxel). It is named by the finest key of its lowest corner voxel and its
// depth (key.at_depth(depth) is its key at its own depth). Its value is the
// maximum log-odds over its voxels, so "occupied" means some voxel in it is
// occupied, "free" that all of them are free, "unknown" anything else; the
// contains_* flags say whether any voxel below is free or unknown. Nodes are
// plain values: they stay valid after the map changes (and describe the map
// as it was when they were made).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "umbra/core/color.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

struct Node {
  Key key;                    ///< finest key of the node's lowest corner voxel
  int depth = 0;              ///< 0: a voxel; d: a node of 8^d voxels
  Vec3d center;               ///< metres
  double size = 0.0;          ///< edge length, metres
  float log_odds = 0.0f;      ///< maximum over the node's voxels
  OccupancyState state = OccupancyState::unknown;
  bool contains_free = false;     ///< some voxel in the node is free
  bool contains_unknown = false;  ///< some voxel in the node is unknown
  /// The node has children in the map (it is not a leaf of the tree). A
  /// childless node's value holds for every voxel it covers.
  bool has_children = false;
  std::optional<Rgb> color;   ///< maps with color: the node's (average) color, when it has one

  [[nodiscard]] bool contains_occupied() const { return state == OccupancyState::occupied; }
  /// Morton code of key (the node's first finest voxel).
  [[nodiscard]] std::uint64_t code() const { return morton::encode(key); }
  [[nodiscard]] Vec3d min_corner() const { return center - Vec3d{size, size, size} * 0.5; }
  [[nodiscard]] Vec3d max_corner() const { return center + Vec3d{size, size, size} * 0.5; }
};

/// How many nodes of each kind a map holds.
struct NodeCounts {
  std::size_t inner = 0;       ///< nodes with eight children
  std::size_t inner_leaf = 0;  ///< childless nodes above the finest depth (each covers 8^d voxels)
  std::size_t leaf = 0;        ///< finest voxels stored
  [[nodiscard]] std::size_t total() const { return inner + inner_leaf + leaf; }
};

}  // namespace umbra
