#include "umbra/io/render_cuts.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "umbra/query/predicate.hpp"

namespace umbra {

namespace {

void check_depth(const OccupancyMap& map, int depth, const char* function) {
  if (depth < 0 || depth > map.depth_levels()) {
    throw std::invalid_argument(std::string(function) + ": depth must be in [0, " +
                                std::to_string(map.depth_levels()) + "], got " + std::to_string(depth));
  }
}

// A slab must cover at least this share of the occupied cells.
constexpr double kMinSlabShare = 0.01;
// Adjacent layers with at least this share of the largest layer's area belong to the slab.
constexpr double kSlabLayerShare = 0.5;

enum class Facing { down, up };  // a ceiling's surface faces down, a floor's up

/// The layers (z key >> depth) of the slab facing `facing`, lowest and
/// highest, as find_ceiling and find_floor describe; nothing when there is none.
std::optional<std::pair<std::uint32_t, std::uint32_t>> find_slab(const OccupancyMap& map, int depth, Facing facing) {
  const std::uint32_t cell = std::uint32_t{1} << depth;  // finest keys per depth-d cell
  const std::uint32_t keys = map.grid().keys_per_axis();
  std::map<std::uint32_t, double> surface;                // layer -> cells with free space beyond
  std::uint32_t lowest = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t highest = 0;
  double occupied_cells = 0;
  for (const Node& node : map.query(pred::leaf() && pred::occupied(), depth)) {
    const std::uint32_t size = std::uint32_t{1} << node.depth;
    const double side = double(size / cell);
    const std::uint32_t first = node.key.z >> depth;
    const std::uint32_t last = (node.key.z + size - 1) >> depth;
    lowest = std::min(lowest, first);
    highest = std::max(highest, last);
    occupied_cells += side * side * double(last - first + 1);
    Key beyond{node.key.x + size / 2, node.key.y + size / 2, 0};
    if (facing == Facing::down) {
      if (node.key.z < cell) continue;  // the grid's bottom: nothing below
      beyond.z = node.key.z - cell;
    } else {
      if (node.key.z + size >= keys) continue;  // the grid's top: nothing above
      beyond.z = node.key.z + size;
    }
    if (map.node(beyond, depth).state == OccupancyState::free) {
      surface[facing == Facing::down ? first : last] += side * side;
    }
  }
  // Candidates: a ceiling's layers in the upper half of [lowest bottom,
  // highest top], a floor's in the lower half.
  const double middle = 0.5 * (double(lowest) + double(highest) + 1.0);
  auto candidate = [&](std::uint32_t layer) {
    return facing == Facing::down ? double(layer) >= middle : double(layer) + 1.0 <= middle;
  };
  std::uint32_t best = 0;
  double largest = 0;
  for (const auto& [layer, area] : surface) {
    if (candidate(layer) && area > largest) {
      best = layer;
      largest = area;
    }
  }
  if (largest == 0 || largest < kMinSlabShare * occupied_cells) return std::nullopt;
  auto part_of_slab = [&](std::uint32_t layer) {
    const auto found = surface.find(layer);
    return candidate(layer) && found != surface.end() && found->second >= kSlabLayerShare * largest;
  };
  std::uint32_t low = best;
  std::uint32_t high = best;
  if (facing == Facing::down) {
    while (low > 0 && part_of_slab(low - 1)) --low;
  } else {
    while (part_of_slab(high + 1)) ++high;
  }
  return std::pair{low, high};
}

}  // namespace

std::optional<CeilingCut> find_ceiling(const OccupancyMap& map, int depth) {
  check_depth(map, depth, "find_ceiling");
  const auto slab = find_slab(map, depth, Facing::down);
  if (!slab) return std::nullopt;
  const double underside = map.grid().min_corner(Key{0, 0, slab->first << depth}).z;
  return CeilingCut{underside, underside - 0.5 * map.grid().node_size(depth)};
}

std::optional<FloorCut> find_floor(const OccupancyMap& map, int depth) {
  check_depth(map, depth, "find_floor");
  const auto slab = find_slab(map, depth, Facing::up);
  if (!slab) return std::nullopt;
  const double top = map.grid().min_corner(Key{0, 0, (slab->second + 1) << depth}).z;
  return FloorCut{top, top + 0.5 * map.grid().node_size(depth)};
}

std::optional<double> middle_section(const OccupancyMap& map, RenderView view, int depth) {
  check_depth(map, depth, "middle_section");
  if (view != RenderView::front && view != RenderView::side) {
    throw std::invalid_argument(std::string("middle_section: a section is for front and side views, got ") +
                                to_string(view));
  }
  const std::size_t axis = view == RenderView::front ? 1 : 0;
  std::uint32_t low = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t high = 0;
  for (const Node& node : map.query(pred::leaf() && pred::occupied(), depth)) {
    low = std::min(low, node.key[axis]);
    high = std::max(high, node.key[axis] + (std::uint32_t{1} << node.depth) - 1);
  }
  if (low > high) return std::nullopt;
  // The depth-d layer holding the middle finest key, and its centre.
  const std::uint32_t middle = low + (high - low) / 2;
  const std::uint32_t first = (middle >> depth) << depth;
  Key key{0, 0, 0};
  key[axis] = first;
  return map.grid().center(key, depth)[axis];
}

}  // namespace umbra
