// What `umbra view` puts in its page: the map's numbers and its nodes at a
// range of depths, as compact binary layers.
//
// For each depth d shown and each state (occupied, free, unknown) a layer
// holds the nodes of map.query(pred::leaf() && pred::<state>(), d); unknown
// nodes are limited to those overlapping the known space (its bounding box,
// MapStatistics::known_min/max) and clipped to it, since the unknown rest
// of the map is the whole world. The finest depth shown is the finest whose
// occupied node count is at most `budget`; up to 7 coarser depths follow. A
// free or unknown layer above the budget is counted but left out of the page.
//
// Layer format (little endian), n nodes, columns one after the other:
//   x[n] y[n] z[n]     lower corner, in finest voxels from the known space's
//                      lowest corner (ViewerData::origin_key)
//   sx[n] sy[n] sz[n]  edge lengths in finest voxels
//   r[n] g[n] b[n]     occupied layers of maps with colour only (uint8; a
//                      node without a colour is 150, 150, 150)
// The integer columns are uint16 when every value fits (key_bytes 2), else
// uint32. The layer is compressed with zlib (the page inflates it with the
// browser's DecompressionStream("deflate")).
//
// Cost: per depth shown, three counts and up to three query walks; memory:
// the compressed layers (a few bytes per node).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "umbra/core/morton.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::cli {

inline constexpr std::size_t kDefaultViewerBudget = 2'000'000;
/// Coarser depths shown after the finest one.
inline constexpr int kViewerExtraDepths = 7;

enum class ViewerState : unsigned char { occupied, free, unknown };
const char* to_string(ViewerState state);

struct ViewerLayer {
  int depth = 0;
  ViewerState state = ViewerState::occupied;
  std::size_t count = 0;               ///< nodes in the layer (also when left out)
  bool embedded = false;               ///< false: over the budget, left out
  std::vector<std::uint8_t> deflated;  ///< the compressed layer (embedded only)
};

struct ViewerData {
  MapStatistics stats;
  std::size_t budget = kDefaultViewerBudget;
  int finest_depth = 0;                ///< finest depth shown
  std::size_t finest_depth_zero_count = 0;  ///< occupied nodes at depth 0
  Key origin_key;                      ///< finest key of the known space's lowest corner
  Key end_key;                         ///< one past its highest finest key, per axis
  int key_bytes = 2;
  std::vector<ViewerLayer> layers;     ///< by depth, then occupied, free, unknown
};

/// Throws std::invalid_argument for a budget of 0.
ViewerData collect_viewer_data(const OccupancyMap& map, std::size_t budget);

/// The page's data block: one JSON object (the numbers, the depths and which
/// layers are embedded as "layer-N" elements). `title` is any text.
std::string viewer_json(const OccupancyMap& map, const ViewerData& data, const std::string& title);

/// Base64 (RFC 4648, with padding).
std::string base64(const std::vector<std::uint8_t>& bytes);

}  // namespace umbra::cli
