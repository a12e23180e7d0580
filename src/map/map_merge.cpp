// OccupancyMap::merge (umbra/map/map_merge.hpp): another map's log-odds
// added to this one's.
//
// Two phases. Under the other map's read lock, its known childless nodes are
// turned into additions for this map's tree (OccupancyTree::NodeDelta), each
// a node of this map's tree: with an offset, a pruned node that lands aligned
// stays one node, one that lands across node borders is covered by the
// fewest aligned nodes; with a transform, every voxel of this map whose
// centre maps back into a known node gets that node's value. Then, with
// this map to itself, the sorted additions go into the tree in one walk
// (add_to_nodes). Planning first keeps the map unchanged when the plan
// fails (a voxel outside the map) and lets a map merge into itself.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "map/map_access.hpp"
#include "map/map_state.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

using NodeDelta = OccupancyTree::NodeDelta;

/// A known childless node of the other map.
struct SourceNode {
  Key first;  // its first finest voxel
  int depth;
  float log_odds;
  Rgb rgb;
  std::uint8_t weight;  // color samples behind rgb, 0: no color
};

/// A color for one finest voxel of this map.
struct ColorDelta {
  std::uint64_t code;
  Rgb rgb;
  std::uint8_t weight;
};

struct MergePlan {
  std::vector<NodeDelta> regions;  // disjoint; apply_plan sorts them by code
  std::vector<ColorDelta> colors;
  std::uint64_t voxels = 0;
};

/// The shortest text that reads back as `value` (0.1, not 0.10000000000000001).
std::string shortest(double value) {
  std::array<char, 32> text{};
  const auto end = std::to_chars(text.data(), text.data() + text.size(), value).ptr;
  return std::string(text.data(), end);
}

void check_compatible(const OccupancyMap& map, const OccupancyMap& other) {
  if (map.resolution() != other.resolution()) {
    throw std::invalid_argument("merge: the maps' resolutions differ (this map " + shortest(map.resolution()) +
                                " m, the other " + shortest(other.resolution()) + " m)");
  }
  if (map.depth_levels() != other.depth_levels()) {
    throw std::invalid_argument("merge: the maps' depth levels differ (this map " +
                                std::to_string(map.depth_levels()) + ", the other " +
                                std::to_string(other.depth_levels()) + ")");
  }
}

std::vector<SourceNode> known_nodes(const OccupancyTree& tree) {
  std::vector<SourceNode> nodes;
  tree.for_each_leaf([&](NodeRef node, std::uint64_t code) {
    const float value = tree.log_odds(node);
    if (value == 0.0f) return;  // never observed: adds nothing
    const std::uint8_t weight = tree.color_weight(node);  // 0 without color
    nodes.push_back({morton::decode(code), node.depth, value, weight != 0 ? *tree.color(node) : Rgb{}, weight});
  });
  return nodes;
}

std::string key_text(std::int64_t x, std::int64_t y, std::int64_t z) {
  return "(" + std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(z) + ")";
}

/// Appends the fewest aligned nodes of depth <= `depth` that tile the cube
/// [lo, lo + 2^size_depth) on each axis, starting from the node at `depth`
/// whose first voxel is `node`.
void cover(Key node, int depth, const std::array<std::int64_t, 3>& lo, std::int64_t size, float delta,
           std::vector<NodeDelta>& out) {
  const std::int64_t side = std::int64_t{1} << depth;
  bool inside = true;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t first = node[axis];
    if (first + side <= lo[axis] || first >= lo[axis] + size) return;  // disjoint
    inside &= first >= lo[axis] && first + side <= lo[axis] + size;
  }
  if (inside) {
    out.push_back({morton::encode(node), depth, delta});
    return;
  }
  const std::uint32_t half = std::uint32_t{1} << (depth - 1);
  for (unsigned slot = 0; slot < 8; ++slot) {
    const Key child{node.x + ((slot & 1u) != 0 ? half : 0), node.y + ((slot & 2u) != 0 ? half : 0),
                    node.z + ((slot & 4u) != 0 ? half : 0)};
    cover(child, depth - 1, lo, size, delta, out);
  }
}

MergePlan plan_offset(const std::vector<SourceNode>& nodes, const Grid& grid, VoxelOffset offset, bool colors) {
  MergePlan plan;
  const std::int64_t keys = grid.keys_per_axis();
  const std::array<std::int64_t, 3> shift{offset.x, offset.y, offset.z};
  for (const SourceNode& node : nodes) {
    const std::int64_t size = std::int64_t{1} << node.depth;
    std::array<std::int64_t, 3> lo{};
    bool aligned = true;
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::int64_t{node.first[axis]} + shift[axis];
      if (lo[axis] < 0 || lo[axis] + size > keys) {
        throw std::out_of_range("merge: the other map's voxel " +
                                key_text(node.first.x, node.first.y, node.first.z) + " moved by " +
                                key_text(offset.x, offset.y, offset.z) + " lands outside this map (keys 0 to " +
                                std::to_string(keys - 1) + ")");
      }
      aligned &= lo[axis] % size == 0;
    }
    const std::size_t before = plan.regions.size();
    if (aligned) {
      plan.regions.push_back({morton::encode(Key{std::uint32_t(lo[0]), std::uint32_t(lo[1]), std::uint32_t(lo[2])}),
                              node.depth, node.log_odds});
    } else {
      // Across node borders: start from the (up to 8) nodes of its size it meets.
      for (unsigned slot = 0; slot < 8; ++slot) {
        Key start;
        bool distinct = true;
        for (int axis = 0; axis < 3; ++axis) {
          const bool upper = (slot >> axis & 1u) != 0;
          const std::int64_t first = (lo[axis] >> node.depth) << node.depth;
          // The upper node exists only when the cube is not aligned on this axis.
          if (upper && first == lo[axis]) distinct = false;
          start[axis] = static_cast<std::uint32_t>(upper ? first + size : first);
        }
        if (distinct) cover(start, node.depth, lo, size, node.log_odds, plan.regions);
      }
    }
    plan.voxels += std::uint64_t(size * size * size);
    if (colors && node.weight != 0) {
      // Color lives on voxels: every voxel of the landed cube.
      for (std::size_t i = before; i < plan.regions.size(); ++i) {
        const NodeDelta& region = plan.regions[i];
        const std::uint64_t count = std::uint64_t{1} << (3 * region.depth);
        for (std::uint64_t v = 0; v < count; ++v) plan.colors.push_back({region.code + v, node.rgb, node.weight});
      }
    }
  }
  return plan;
}

/// Whether `transform` moves by whole voxels only (then it merges as an offset).
std::optional<VoxelOffset> whole_voxel_shift(const Pose& transform, double resolution) {
  for (std::size_t row = 0; row < 3; ++row) {
    for (std::size_t column = 0; column < 3; ++column) {
      if (transform.m[row][column] != (row == column ? 1.0 : 0.0)) return std::nullopt;
    }
  }
  std::array<std::int64_t, 3> shift{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double voxels = transform.m[axis][3] / resolution;
    if (voxels != std::nearbyint(voxels) || std::abs(voxels) > 1e15) return std::nullopt;
    // Exactly whole: t = n * resolution with c - t in the rule landing on the
    // same voxel as k - n (a centre is half a voxel from every border).
    const auto whole = static_cast<std::int64_t>(voxels);
    if (static_cast<double>(whole) * resolution != transform.m[axis][3]) return std::nullopt;
    shift[axis] = whole;
  }
  return VoxelOffset{shift[0], shift[1], shift[2]};
}

/// The other map's voxel whose value this map's voxel `target` takes under
/// `transform`: the one holding T^-1 c, c the target's centre.
std::optional<Key> merge_source_key(const Grid& grid, const Pose& transform, Key target) {
  // R^T (c - t), in double, each sum left to right (the documented rule).
  const Vec3d c = grid.center(target);
  const auto& m = transform.m;
  const double dx = c.x - m[0][3];
  const double dy = c.y - m[1][3];
  const double dz = c.z - m[2][3];
  const Vec3d p{m[0][0] * dx + m[1][0] * dy + m[2][0] * dz, m[0][1] * dx + m[1][1] * dy + m[2][1] * dz,
                m[0][2] * dx + m[1][2] * dy + m[2][2] * dz};
  return grid.key_checked(p);
}

MergePlan plan_transform(const std::vector<SourceNode>& nodes, const Grid& grid, const Pose& transform,
                         bool colors) {
  MergePlan plan;
  const auto& m = transform.m;
  for (const SourceNode& node : nodes) {
    // The node's cube moved into this map: its bounding box bounds the
    // voxels whose centres can map back into it.
    const Vec3d corner = grid.min_corner(node.first, node.depth);
    const double side = grid.node_size(node.depth);
    Vec3d lo{1e300, 1e300, 1e300};
    Vec3d hi{-1e300, -1e300, -1e300};
    for (unsigned c = 0; c < 8; ++c) {
      const double x = corner.x + ((c & 1u) != 0 ? side : 0.0);
      const double y = corner.y + ((c & 2u) != 0 ? side : 0.0);
      const double z = corner.z + ((c & 4u) != 0 ? side : 0.0);
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double moved = m[axis][0] * x + m[axis][1] * y + m[axis][2] * z + m[axis][3];
        lo[axis] = std::min(lo[axis], moved);
        hi[axis] = std::max(hi[axis], moved);
      }
    }
    std::array<std::uint32_t, 3> first{};
    std::array<std::uint32_t, 3> last{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::optional<std::uint32_t> a = grid.axis_key(lo[axis]);
      const std::optional<std::uint32_t> b = grid.axis_key(hi[axis]);
      if (!a || !b) {
        throw std::out_of_range("merge: the other map's node at voxel " +
                                key_text(node.first.x, node.first.y, node.first.z) + " (depth " +
                                std::to_string(node.depth) + ") lands outside this map under the transform");
      }
      first[axis] = *a;
      last[axis] = *b;
    }
    const Key source_node = node.first.at_depth(node.depth);
    for (std::uint32_t kz = first[2]; kz <= last[2]; ++kz) {
      for (std::uint32_t ky = first[1]; ky <= last[1]; ++ky) {
        for (std::uint32_t kx = first[0]; kx <= last[0]; ++kx) {
          const Key target{kx, ky, kz};
          const std::optional<Key> source = merge_source_key(grid, transform, target);
          if (!source || source->at_depth(node.depth) != source_node) continue;
          const std::uint64_t code = morton::encode(target);
          plan.regions.push_back({code, 0, node.log_odds});
          ++plan.voxels;
          if (colors && node.weight != 0) plan.colors.push_back({code, node.rgb, node.weight});
        }
      }
    }
  }
  return plan;
}

/// Merges runs of eight sibling additions of one value into their parent,
/// repeatedly: fewer, coarser additions keep the walk short and let the
/// tree keep pruned nodes whole. `regions` is sorted and disjoint.
void coarsen(std::vector<NodeDelta>& regions) {
  std::vector<NodeDelta> out;
  out.reserve(regions.size());
  for (const NodeDelta& region : regions) {
    out.push_back(region);
    for (;;) {
      if (out.size() < 8) break;
      const NodeDelta& first = out[out.size() - 8];
      const int depth = first.depth;
      const std::uint64_t step = std::uint64_t{1} << (3 * depth);
      // The parent's first voxel, aligned at depth + 1.
      if (depth >= kMaxDepthLevels - 1 || (first.code & ((step << 3) - 1)) != 0) break;
      bool siblings = true;
      for (std::size_t i = 1; i < 8 && siblings; ++i) {
        const NodeDelta& next = out[out.size() - 8 + i];
        siblings = next.depth == depth && next.delta == first.delta && next.code == first.code + i * step;
      }
      if (!siblings) break;
      const NodeDelta parent{first.code, depth + 1, first.delta};
      out.resize(out.size() - 8);
      out.push_back(parent);
    }
  }
  regions.swap(out);
}

/// The weighted average of a voxel's color and the other map's.
std::pair<Rgb, std::uint8_t> blend_colors(std::optional<Rgb> own, std::uint8_t own_weight, Rgb add,
                                          std::uint8_t add_weight) {
  if (!own || own_weight == 0) return {add, add_weight};
  const unsigned total = unsigned{own_weight} + add_weight;
  auto mix = [&](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>((a * unsigned{own_weight} + b * unsigned{add_weight} + total / 2) / total);
  };
  return {Rgb{mix(own->r, add.r), mix(own->g, add.g), mix(own->b, add.b)},
          static_cast<std::uint8_t>(std::min(total, 255u))};
}

MergeStats apply_plan(detail::MapState& state, MergePlan& plan) {
  // Leaves come in Morton order, so an aligned offset keeps them sorted: check before sorting.
  const auto by_code = [](const NodeDelta& a, const NodeDelta& b) { return a.code < b.code; };
  if (!std::is_sorted(plan.regions.begin(), plan.regions.end(), by_code)) {
    std::sort(plan.regions.begin(), plan.regions.end(), by_code);
  }
  coarsen(plan.regions);
  // The map to itself, as for any change (occupancy_map.hpp, Concurrency).
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  detail::ClosedGate closed(state.gate);
  OccupancyTree& tree = state.tree;
  tree.add_to_nodes(plan.regions);
  for (const ColorDelta& color : plan.colors) {
    const NodeRef node = tree.find(color.code, 0).node;
    const auto [rgb, weight] = blend_colors(tree.color(node), tree.color_weight(node), color.rgb, color.weight);
    tree.set_color(color.code, rgb, weight);
  }
  if (!plan.regions.empty()) state.journal->record_everything();
  return MergeStats{plan.voxels, plan.regions.size()};
}

}  // namespace

MergeStats OccupancyMap::merge(const OccupancyMap& other, VoxelOffset offset) {
  check_compatible(*this, other);
  const bool colors = color_ && other.color_;
  MergePlan plan = detail::MapAccess::read(
      other, [&](const OccupancyTree& tree) { return plan_offset(known_nodes(tree), grid_, offset, colors); });
  return apply_plan(*state_, plan);
}

MergeStats OccupancyMap::merge(const OccupancyMap& other, const Pose& transform) {
  check_compatible(*this, other);
  if (!transform.is_rigid()) {
    throw std::invalid_argument("merge: the transform is not rigid (its 3 x 3 part must be a rotation)");
  }
  if (const std::optional<VoxelOffset> shift = whole_voxel_shift(transform, resolution())) {
    return merge(other, *shift);
  }
  const bool colors = color_ && other.color_;
  MergePlan plan = detail::MapAccess::read(other, [&](const OccupancyTree& tree) {
    return plan_transform(known_nodes(tree), grid_, transform, colors);
  });
  return apply_plan(*state_, plan);
}

}  // namespace umbra
