// The moving window, for the map's own code (OccupancyMap::move_window and
// the scans of occupancy_map.cpp that follow it).
#pragma once

#include <optional>

#include "map/map_state.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/map/moving_window.hpp"

namespace umbra::detail {

/// Re-centres state's window (it has one) on finest key `position`: hands
/// what leaves to the spill, then forgets it in one exclusive phase (the
/// gate closed only then). The caller holds state.writer. Throws what the
/// spill throws, with the map unchanged.
WindowMove move_window_locked(MapState& state, const Grid& grid, Key position);

/// The box a scan is clipped to.
struct InsertionBox {
  std::optional<Aabb> box;  ///< nothing: no limit
  bool empty = false;       ///< the user's box and the window's do not meet: the scan changes nothing
};
/// The user's bounding box, the window's box (when placed), or their intersection.
InsertionBox insertion_box(const MapState& state, const Grid& grid);

}  // namespace umbra::detail
