// MovingWindow: a map that keeps only a box around the robot, so that a long
// run's memory stays bounded (OccupancyMap::set_moving_window; the rule in
// docs/design.md, "A map that moves").
//
// The box is made of whole nodes of depth `step_depth` (edge
// resolution x 2^step_depth, the "step"): the step holding the robot's
// position and `n = ceil(half_extent / step)` steps on every side of it, cut
// to the map. So every point within half_extent of the robot on each axis
// is in the box. When the robot enters another step the box moves with it
// (by whole steps): what leaves the box is handed to `spill` (a map holding
// just those voxels) and then forgotten: unknown, its nodes freed. Scans
// change only the voxels in the box: rays are clipped to it as by
// set_bounding_box. Because the box is made of whole nodes, a move frees
// whole subtrees: it costs the nodes that leave, not the map.
//
//   umbra::MovingWindow window;
//   window.half_extent = 20.0;                                  // metres
//   window.spill = umbra::spill_to_file("run.umbs");            // or empty: dropped
//   map.set_moving_window(window);
//   map.insert_point_cloud(origin, points);                     // re-centred on origin
#pragma once

#include <cstdint>
#include <functional>

#include "umbra/core/grid.hpp"

namespace umbra {

class OccupancyMap;

struct MovingWindow {
  /// Metres (> 0): the box holds at least every point within this distance
  /// of the robot along each axis.
  double half_extent = 0.0;
  /// The box moves in whole nodes of this depth (0 .. depth_levels - 1); -1
  /// (the default): the largest depth whose edge is at most half_extent / 4,
  /// at least 0.
  int step_depth = -1;
  /// True: every scan first re-centres the box on its sensor origin (the
  /// camera's position for a depth image). False: only move_window moves it.
  bool follow_scans = true;
  /// Receives what leaves the box, before it is forgotten: a map with this
  /// map's settings holding just the voxels that leave (log-odds and
  /// color as they were). Empty: what leaves is dropped. It runs while the
  /// map is held by the move (readers go on; it must not change the map).
  /// If it throws, the move is abandoned and the map is unchanged
  /// (spill_to_file, umbra/io/spill_file.hpp, appends it to a file).
  std::function<void(const OccupancyMap& leaving)> spill;

  /// Throws std::invalid_argument naming the bad field: half_extent not
  /// finite or <= 0, step_depth outside [-1, depth_levels - 1].
  void validate(const Grid& grid) const;
  /// The step depth this window uses on `grid` (step_depth, or the automatic one).
  [[nodiscard]] int step_depth_on(const Grid& grid) const;
};

/// What one move of the window did.
struct WindowMove {
  bool moved = false;              ///< false: the box was already there
  std::uint64_t groups_freed = 0;  ///< groups of eight nodes returned to the tree's pools
  bool spilled = false;            ///< a piece was handed to MovingWindow::spill
};

}  // namespace umbra
