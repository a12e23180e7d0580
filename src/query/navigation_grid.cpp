// project_to_grid (umbra/query/navigation_grid.hpp): two walks over the
// octree nodes that meet the band.
//
// Every node tells, from its summary alone, which of the three states its
// voxels take: occupied (value above the occupied threshold), free
// (contains_free), unknown (contains_unknown). The walks collect, per cell,
// the set of states its band holds (three bits), and the rule turns the set
// into the cell's value at the end. A node's states are the states of
// every column of its footprint when
//  - it is childless (or, auto-pruning off, its children are childless and
//    equal): one value throughout;
//  - it holds one state only: then every voxel has it;
//  - it is no wider than a cell and wholly inside the band: its footprint
//    is one cell (or part of one), whose band holds all its voxels.
// Any other node is opened. A node that only partly overlaps the band must
// be opened unless one of the first two holds: its states may come from
// voxels outside the band. A node of depth 1 is opened inline (its eight
// voxels classified in a loop, no call each).
#include "umbra/query/navigation_grid.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/memory_budget.hpp"
#include "map/map_access.hpp"
#include "query/node_context.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {

std::string_view to_string(ProjectionRule rule) {
  return rule == ProjectionRule::all_known ? "all_known" : "any_free";
}

ProjectionRule parse_projection_rule(std::string_view name) {
  if (name == "all_known") return ProjectionRule::all_known;
  if (name == "any_free") return ProjectionRule::any_free;
  throw std::invalid_argument("unknown projection rule '" + std::string(name) +
                              "' (the rules: all_known, any_free)");
}

void ProjectionOptions::validate() const {
  if (!std::isfinite(z_min)) throw std::invalid_argument("z_min must be a finite height, got " + std::to_string(z_min));
  if (!std::isfinite(z_max)) throw std::invalid_argument("z_max must be a finite height, got " + std::to_string(z_max));
  if (!(z_min < z_max)) {
    std::ostringstream text;
    text << "z_min must be below z_max, got z_min " << z_min << " and z_max " << z_max;
    throw std::invalid_argument(text.str());
  }
  if (depth < 0) throw std::invalid_argument("depth must be >= 0, got " + std::to_string(depth));
}

namespace {

using detail::child_key;

constexpr std::uint8_t kOccupied = 1;
constexpr std::uint8_t kFree = 2;
constexpr std::uint8_t kUnknown = 4;

/// Cells in finest-key-derived indices: cell (i, j) covers finest x keys
/// [i << depth, (i + 1) << depth).
struct CellBlock {
  std::uint32_t x0, y0, x1, y1;  ///< inclusive
};

class Projection {
 public:
  Projection(const OccupancyTree& tree, int cell_depth, std::uint32_t band_lo, std::uint32_t band_hi)
      : tree_(tree), t_(tree.thresholds()), cell_depth_(cell_depth), band_lo_(band_lo), band_hi_(band_hi) {}

  /// Pass 1: the block of cells whose band holds a known voxel; false when none does.
  bool find_extent(CellBlock& extent) {
    extend(tree_.root(), Key{0, 0, 0});
    if (!found_) return false;
    extent = extent_;
    return true;
  }

  /// Pass 2: the states of every cell of `extent`, row-major from its lowest y.
  std::vector<std::uint8_t> collect_states(const CellBlock& extent) {
    extent_ = extent;
    width_ = extent.x1 - extent.x0 + 1;
    states_.assign(std::size_t{width_} * (extent.y1 - extent.y0 + 1), 0);
    collect(tree_.root(), Key{0, 0, 0});
    return std::move(states_);
  }

 private:
  [[nodiscard]] std::uint8_t states_of(NodeRef node) const {
    std::uint8_t s = 0;
    if (t_.is_occupied(tree_.log_odds(node))) s |= kOccupied;
    if (tree_.contains_free(node)) s |= kFree;
    if (tree_.contains_unknown(node)) s |= kUnknown;
    return s;
  }
  [[nodiscard]] bool meets_band(Key key, int depth) const {
    const std::uint64_t top = std::uint64_t{key.z} + (std::uint64_t{1} << depth) - 1;
    return top >= band_lo_ && key.z <= band_hi_;
  }
  [[nodiscard]] bool inside_band(Key key, int depth) const {
    const std::uint64_t top = std::uint64_t{key.z} + (std::uint64_t{1} << depth) - 1;
    return key.z >= band_lo_ && top <= band_hi_;
  }
  /// The cells under the node's footprint.
  [[nodiscard]] CellBlock footprint(Key key, int depth) const {
    const std::uint32_t last = static_cast<std::uint32_t>((std::uint64_t{1} << depth) - 1);
    return {key.x >> cell_depth_, key.y >> cell_depth_, (key.x + last) >> cell_depth_, (key.y + last) >> cell_depth_};
  }
  /// Do the node's states hold for every column of its footprint (file comment)?
  [[nodiscard]] bool decides_footprint(NodeRef node, Key key, std::uint8_t states) const {
    if (!tree_.has_children(node) || tree_.all_children_same(node)) return true;
    if (states == kOccupied || states == kFree || states == kUnknown) return true;
    return node.depth <= cell_depth_ && inside_band(key, node.depth);
  }

  void extend(NodeRef node, Key key) {
    if (!meets_band(key, node.depth)) return;
    const std::uint8_t states = states_of(node);
    if ((states & (kOccupied | kFree)) == 0) return;  // nothing known below
    const CellBlock cells = footprint(key, node.depth);
    if (found_ && cells.x0 >= extent_.x0 && cells.y0 >= extent_.y0 && cells.x1 <= extent_.x1 &&
        cells.y1 <= extent_.y1) {
      return;  // cannot widen the extent
    }
    // Every column of the footprint holds a known band voxel when the node
    // is childless (known throughout), holds no unknown voxel (each column
    // of it meets the band), or lies in one cell and wholly inside the band.
    const bool known_everywhere = !tree_.has_children(node) || tree_.all_children_same(node) ||
                                  (states & kUnknown) == 0 ||
                                  (node.depth <= cell_depth_ && inside_band(key, node.depth));
    if (known_everywhere) {
      if (!found_) {
        extent_ = cells;
        found_ = true;
      } else {
        extent_ = {std::min(extent_.x0, cells.x0), std::min(extent_.y0, cells.y0), std::max(extent_.x1, cells.x1),
                   std::max(extent_.y1, cells.y1)};
      }
      return;
    }
    for (unsigned slot = 0; slot < 8; ++slot) extend(tree_.child(node, slot), child_key(key, node.depth, slot));
  }

  void collect(NodeRef node, Key key) {
    if (!meets_band(key, node.depth)) return;
    const CellBlock cells = footprint(key, node.depth);
    const CellBlock clipped{std::max(cells.x0, extent_.x0), std::max(cells.y0, extent_.y0),
                            std::min(cells.x1, extent_.x1), std::min(cells.y1, extent_.y1)};
    if (clipped.x0 > clipped.x1 || clipped.y0 > clipped.y1) return;
    const std::uint8_t states = states_of(node);
    if (decides_footprint(node, key, states)) {
      for (std::uint32_t y = clipped.y0; y <= clipped.y1; ++y) {
        std::uint8_t* row = states_.data() + std::size_t{y - extent_.y0} * width_ - extent_.x0;
        for (std::uint32_t x = clipped.x0; x <= clipped.x1; ++x) row[x] |= states;
      }
      return;
    }
    if (node.depth == 1) {
      // The children are voxels: classified here rather than by a call each
      // (most nodes a projection opens are voxels at the band's faces and
      // along surfaces; the calls were most of its time).
      for (unsigned slot = 0; slot < 8; ++slot) {
        const Key voxel = child_key(key, 1, slot);
        if (voxel.z < band_lo_ || voxel.z > band_hi_) continue;
        const std::uint32_t x = voxel.x >> cell_depth_, y = voxel.y >> cell_depth_;
        if (x < extent_.x0 || x > extent_.x1 || y < extent_.y0 || y > extent_.y1) continue;
        const float value = tree_.log_odds(tree_.child(node, slot));
        states_[std::size_t{y - extent_.y0} * width_ + (x - extent_.x0)] |=
            t_.is_occupied(value) ? kOccupied : t_.is_free(value) ? kFree : kUnknown;
      }
      return;
    }
    for (unsigned slot = 0; slot < 8; ++slot) collect(tree_.child(node, slot), child_key(key, node.depth, slot));
  }

  const OccupancyTree& tree_;
  LogOddsThresholds t_;
  int cell_depth_;
  std::uint32_t band_lo_;
  std::uint32_t band_hi_;
  CellBlock extent_{};
  bool found_ = false;
  std::uint32_t width_ = 0;
  std::vector<std::uint8_t> states_;
};

GridCell cell_value(std::uint8_t states, ProjectionRule rule) {
  if (states & kOccupied) return GridCell::occupied;
  const bool free = rule == ProjectionRule::all_known ? states == kFree : (states & kFree) != 0;
  return free ? GridCell::free : GridCell::unknown;
}

}  // namespace

NavigationGrid project_to_grid(const OccupancyMap& map, const ProjectionOptions& options) {
  options.validate();
  const Grid& grid = map.grid();
  if (options.depth > grid.depth_levels()) {
    throw std::invalid_argument("depth must be at most the map's depth_levels " +
                                std::to_string(grid.depth_levels()) + ", got " + std::to_string(options.depth));
  }
  // The band's voxel rows: key(z_min) .. key(z_max), cut to the map.
  const double half = grid.half_extent();
  if (options.z_max < -half || options.z_min >= half) {
    std::ostringstream text;
    text << "the band from z_min " << options.z_min << " to z_max " << options.z_max
         << " lies outside the map, which spans z from " << -half << " to " << half;
    throw std::out_of_range(text.str());
  }
  const std::uint32_t band_lo = grid.axis_key(options.z_min).value_or(0);
  const std::uint32_t band_hi = grid.axis_key(options.z_max).value_or(grid.keys_per_axis() - 1);

  NavigationGrid result;
  result.depth = options.depth;
  result.resolution = grid.node_size(options.depth);
  CellBlock extent{};
  std::vector<std::uint8_t> states;
  const bool known = detail::MapAccess::read(map, [&](const OccupancyTree& tree) {
    Projection projection(tree, options.depth, band_lo, band_hi);
    if (!projection.find_extent(extent)) return false;
    // Two bytes a cell (the states, then the values): a band known over a
    // large area at a fine depth is refused before it is allocated.
    const std::uint64_t cells = std::uint64_t{extent.x1 - extent.x0 + 1} * (extent.y1 - extent.y0 + 1);
    detail::require_memory("project_to_grid",
                           "a grid of " + std::to_string(extent.x1 - extent.x0 + 1) + " x " +
                               std::to_string(extent.y1 - extent.y0 + 1) + " cells",
                           2 * cells);
    states = projection.collect_states(extent);
    return true;
  });
  if (!known) return result;
  result.width = extent.x1 - extent.x0 + 1;
  result.height = extent.y1 - extent.y0 + 1;
  const Vec3d corner = grid.min_corner(Key{extent.x0 << options.depth, extent.y0 << options.depth, 0});
  result.origin_x = corner.x;
  result.origin_y = corner.y;
  result.cells.resize(states.size());
  std::transform(states.begin(), states.end(), result.cells.begin(),
                 [&](std::uint8_t s) { return cell_value(s, options.rule); });
  return result;
}

}  // namespace umbra
