// The cuts `umbra render` makes by default, so that a view of a building
// shows its rooms rather than its roof or its outer wall (map_render.hpp
// draws them through RenderOptions::min_z, max_z and section).
//
// find_ceiling: a ceiling, seen from a sensor inside the room, is a layer of
// occupied nodes with observed free space directly below it. For each
// occupied node at `depth` the depth-d node below its centre is looked up;
// when it is free the node is an overhang, counted by its footprint (in
// depth-d cells) in the layer of its lowest cells. The ceiling is found
// among the layers whose bottom lies in the upper half of the occupied
// height range: the layer with the largest overhang area, provided that
// area is at least 1% of the occupied cells (a few lintels or lamps are not
// a ceiling), and below it every adjacent layer with at least half that
// area (lidar spreads a ceiling over two or three layers). The cut keeps
// everything below the lowest of them. Maps without a ceiling (open scans,
// outdoor maps whose highest overhangs are scattered) give nothing. The
// FR-079 corridor (geb079.bt, 8 cm) gives a ceiling at 2.64 m, the demo
// building (20 cm) one at 2.8 m.
//
// find_floor: the same upside down: occupied nodes with free space directly
// above them, counted in the layer of their highest cells, among the layers
// whose top lies in the lower half; from the largest, every adjacent layer
// above with at least half its area. The cut keeps everything above the
// highest of them (a top view colored by state then shows free floor space
// between the walls, as a 2D occupancy grid does). geb079.bt: the floor's
// top at 0.0 m; the demo building: 0.2 m.
//
// middle_section: the centre of the depth-d layer, across the view's axis
// (front: y, side: x), that holds the middle of the occupied nodes' extent on
// that axis.
//
// Cost: one query walk over the occupied nodes at `depth`, and for
// find_ceiling and find_floor one node() lookup per node (a descent of the
// tree).
#pragma once

#include <optional>

#include "umbra/io/map_render.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

struct CeilingCut {
  double underside_z = 0.0;  ///< metres: the bottom of the ceiling's lowest layer
  /// The RenderOptions::max_z that leaves the ceiling out and keeps the layer
  /// below it: the centre of that layer.
  double max_z = 0.0;
};

struct FloorCut {
  double top_z = 0.0;  ///< metres: the top of the floor's highest layer
  /// The RenderOptions::min_z that leaves the floor out and keeps the layer
  /// above it: the centre of that layer.
  double min_z = 0.0;
};

/// The ceiling of `map` at `depth` as described above, or nothing. Throws
/// std::invalid_argument for a depth outside [0, map.depth_levels()].
std::optional<CeilingCut> find_ceiling(const OccupancyMap& map, int depth = 0);

/// The floor of `map` at `depth` as described above, or nothing. Throws
/// std::invalid_argument for a depth outside [0, map.depth_levels()].
std::optional<FloorCut> find_floor(const OccupancyMap& map, int depth = 0);

/// The RenderOptions::section through the middle of the occupied nodes for a
/// front or side view; nothing for a map without occupied nodes. Throws
/// std::invalid_argument for a top or iso view or a bad depth.
std::optional<double> middle_section(const OccupancyMap& map, RenderView view, int depth = 0);

}  // namespace umbra
