// What `umbra view` puts in its page: the map's numbers and its nodes at a
// range of depths, as compact binary layers.
//
// For each depth d shown and each state (occupied, free, unknown) a layer
// holds the nodes of map.query(pred::leaf() && pred::<state>(), d); unknown
// nodes are limited to those overlapping the known space (its bounding box,
// MapStatistics::known_min/max), since the unknown rest of the map is the
// whole world. The page clips every node to that box (unknown nodes and
// coarse nodes of any state reach beyond it). The finest depth shown is the
// finest whose occupied node count is at most `budget` and at least
// depth_levels - 17 (see the codes below); up to 7 coarser depths follow. A
// free or unknown layer above the budget is counted but left out of the page.
//
// Layer format (a layer of n nodes at depth d, sorted by code):
//   n varints     code deltas: code = morton::encode(key >> d) of the node's
//                 finest key (its lowest corner), x in bit 0, y bit 1, z
//                 bit 2; each code minus the previous one (the first minus
//                 0), 7 bits a byte, low bits first, high bit = more follows
//   n bytes       node depth - d (the node's edge is 2^depth finest voxels)
//   3 n bytes     occupied layers of maps with color only: the colors in
//                 5-6-5 bits (r >> 3, g >> 2, b >> 3; a node without a color
//                 is 150, 150, 150), red column, green, blue, each value
//                 minus the previous one in its column, modulo 256
// Codes of keys >> d fit 51 bits (17 per axis, as JavaScript numbers hold
// 53 bits exactly) when d >= depth_levels - 17. Sorted codes, deltas and the
// 5-6-5 colors make a layer compress to about 1.7 bytes per occupied
// colored node (4 mm TUM map, zlib level 9) where the previous format, six
// 16-bit columns and 8-bit colors, took 3.7. The layer is compressed with
// zlib (the page inflates it with the browser's DecompressionStream
// ("deflate")) and embedded as base64.
//
// Cost: per depth shown, three counts and up to three query walks, a sort of
// each layer's codes; memory: one layer's nodes (16 bytes each) while it is
// encoded, then the compressed layers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "umbra/core/morton.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::cli {

inline constexpr std::size_t kDefaultViewerBudget = 2'000'000;
/// Coarser depths shown after the finest one.
inline constexpr int kViewerExtraDepths = 7;
/// Bits per axis of a layer's codes (3 x 17 = 51 bits fit a JavaScript number).
inline constexpr int kViewerCodeBitsPerAxis = 17;

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
  std::vector<ViewerLayer> layers;     ///< by depth, then occupied, free, unknown
  /// The height cut the page starts with (RenderOptions::max_z of
  /// find_ceiling at the finest depth shown), metres; nothing without a ceiling.
  std::optional<double> ceiling_cut;
};

/// Throws std::invalid_argument for a budget of 0.
ViewerData collect_viewer_data(const OccupancyMap& map, std::size_t budget);

/// The page's data block: one JSON object (the numbers, the depths and which
/// layers are embedded as "layer-N" elements). `title` is any text.
std::string viewer_json(const OccupancyMap& map, const ViewerData& data, const std::string& title);

/// Base64 (RFC 4648, with padding).
std::string base64(const std::vector<std::uint8_t>& bytes);

}  // namespace umbra::cli
