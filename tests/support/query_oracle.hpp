// The query layer's oracle: random maps, every voxel's value read through
// the simplest public lookup (OccupancyMap::node(key, 0)), and the tree's
// nodes enumerated naively through point lookups, so that the pruned walks
// of src/query can be compared with brute force over a dense grid.
//
// Nothing here uses the query layer's walks or compiled predicates; shapes
// are tested by their public definitions (shapes.hpp), segments by the test
// DenseGrid's own copy of OctoMap's ray walk.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "umbra/core/log_odds.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

struct RandomMapSpec {
  int depth_levels = 5;
  double resolution = 0.1;
  bool auto_prune = true;
  unsigned seed = 1;
  /// Fraction of the space the uniform blocks cover (large pruned nodes).
  double block_fill = 0.4;
  /// Single voxels set to random values.
  int scattered_voxels = 300;
  /// Scans of random rays inserted with the discrete integrator.
  int scans = 2;
};

/// A map mixing pruned uniform blocks (occupied, free, unknown, odd values),
/// scattered voxels and a few scans: every node kind and indicator occurs.
OccupancyMap random_map(const RandomMapSpec& spec);

/// Every finest voxel's log-odds, read with map.node(key, 0).
class DenseValues {
 public:
  explicit DenseValues(const OccupancyMap& map);
  [[nodiscard]] std::uint32_t size() const { return size_; }
  [[nodiscard]] float at(Key key) const { return values_[index(key)]; }

  /// Brute-force summaries of the depth-`depth` node whose lowest voxel is `base`.
  struct Summary {
    float max;
    bool any_free;
    bool any_unknown;
    bool all_equal;
  };
  [[nodiscard]] Summary summarize(Key base, int depth, const LogOddsThresholds& thresholds) const;

 private:
  [[nodiscard]] std::size_t index(Key key) const { return (std::size_t{key.z} * size_ + key.y) * size_ + key.x; }
  std::uint32_t size_;
  std::vector<float> values_;
};

/// A node of the tree as the naive enumeration finds it.
struct OracleNode {
  Key key;  ///< lowest finest voxel
  int depth;
  bool leaf;  ///< no children at the query depth
  friend bool operator==(const OracleNode&, const OracleNode&) = default;
};

/// Every node a query at `query_depth` walks over, parents before children in
/// Morton order, found with map.node() lookups only: a node is a leaf when
/// it is at the query depth, has no children, or (auto-pruning off) its
/// eight children are childless and equal.
std::vector<OracleNode> enumerate_nodes(const OccupancyMap& map, int query_depth);

/// Lowest finest key of child `slot` of the node (key, depth).
Key child_key(Key key, int depth, unsigned slot);

}  // namespace umbra::test
