// A map that moves: MovingWindow, OccupancyMap's window (set_moving_window,
// move_window) and the box that scans are clipped to (docs/design.md, "A
// map that moves").
#include "map/map_window.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "map/map_copy.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

void MovingWindow::validate(const Grid& grid) const {
  if (!(std::isfinite(half_extent) && half_extent > 0.0)) {
    throw std::invalid_argument("moving window half_extent must be finite and > 0 (metres), got " +
                                std::to_string(half_extent));
  }
  if (step_depth < -1 || step_depth >= grid.depth_levels()) {
    throw std::invalid_argument("moving window step_depth must be -1 (automatic) or in [0, " +
                                std::to_string(grid.depth_levels() - 1) + "], got " + std::to_string(step_depth));
  }
}

int MovingWindow::step_depth_on(const Grid& grid) const {
  if (step_depth >= 0) return step_depth;
  // Steps of about a quarter of the half extent: a move frees a slab an
  // eighth of the box thick, and the box overshoots half_extent by under a step.
  int depth = 0;
  while (depth + 1 < grid.depth_levels() && grid.resolution() * std::ldexp(1.0, depth + 1) <= half_extent / 4.0) {
    ++depth;
  }
  return depth;
}

namespace detail {
namespace {

/// The window's box around finest key `position`: the step holding it and
/// n steps on every side, cut to the map.
OccupancyTree::KeyBox window_keys(const MovingWindow& window, const Grid& grid, Key position) {
  const int step = window.step_depth_on(grid);
  const double step_metres = grid.resolution() * std::ldexp(1.0, step);
  const auto steps = static_cast<std::uint64_t>(std::ceil(window.half_extent / step_metres));
  const std::uint64_t last_step = (std::uint64_t{grid.keys_per_axis()} >> step) - 1;
  OccupancyTree::KeyBox box;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint64_t centre = position[axis] >> step;
    const std::uint64_t lo = centre >= steps ? centre - steps : 0;
    const std::uint64_t hi = std::min(centre + steps, last_step);
    box.lo[axis] = static_cast<std::uint32_t>(lo << step);
    box.hi[axis] = static_cast<std::uint32_t>(((hi + 1) << step) - 1);
  }
  return box;
}

bool same_box(const OccupancyTree::KeyBox& a, const OccupancyTree::KeyBox& b) { return a.lo == b.lo && a.hi == b.hi; }

}  // namespace

WindowMove move_window_locked(MapState& state, const Grid& grid, Key position) {
  UMBRA_ASSERT(state.window.has_value());
  const OccupancyTree::KeyBox keep = window_keys(*state.window, grid, position);
  WindowMove move;
  if (state.window_keys && same_box(*state.window_keys, keep)) return move;
  move.moved = true;
  const VoxelBox kept{keep.lo, keep.hi};
  if (state.window->spill) {
    // What leaves, as a map of its own, while readers go on (this thread is
    // the only writer, so the tree holds still).
    OccupancyMap leaving(MapConfig{grid.resolution(), grid.depth_levels(), state.sensor, state.thresholds,
                                   state.tree.has_color()});
    if (!state.tree.auto_prune()) leaving.set_auto_prune(false);
    const bool any = copy_voxels(state.tree, leaving, [&](Key corner, int depth) {
      return (std::uint64_t{1} << (3 * depth)) - kept.voxels_inside(corner, depth);
    });
    if (any) {
      if (state.tree.auto_prune()) leaving.prune();
      state.window->spill(leaving);  // throws: nothing has changed yet
      move.spilled = true;
    }
  }
  ClosedGate closed(state.gate);
  if (state.journal->active()) {
    std::vector<OccupancyTree::DecayChange> changes;
    move.groups_freed = state.tree.forget_outside(keep, &changes, ChangeJournal::kJournalDepth);
    for (const OccupancyTree::DecayChange& change : changes) state.journal->record(change.code, change.depth);
  } else {
    move.groups_freed = state.tree.forget_outside(keep);
  }
  state.window_keys = keep;
  return move;
}

InsertionBox insertion_box(const MapState& state, const Grid& grid) {
  if (!state.window_keys) return {state.bounding_box, false};
  // The box's keys in metres, each face pulled in by a millionth of a voxel
  // so that the keys the integrator takes from it (umbra/map/voxel_box.hpp:
  // a corner on a face takes the voxel above) are exactly the window's.
  const double inset = grid.resolution() * 1e-6;
  const Vec3d lo = grid.min_corner(state.window_keys->lo);
  const Vec3d hi = grid.min_corner(state.window_keys->hi);
  Aabb box{{lo.x + inset, lo.y + inset, lo.z + inset},
           {hi.x + grid.resolution() - inset, hi.y + grid.resolution() - inset, hi.z + grid.resolution() - inset}};
  if (state.bounding_box) {
    for (int axis = 0; axis < 3; ++axis) {
      box.min[axis] = std::max(box.min[axis], state.bounding_box->min[axis]);
      box.max[axis] = std::min(box.max[axis], state.bounding_box->max[axis]);
      if (box.min[axis] > box.max[axis]) return {std::nullopt, true};
    }
  }
  return {box, false};
}

}  // namespace detail

void OccupancyMap::set_moving_window(const std::optional<MovingWindow>& window) {
  if (window) window->validate(grid_);
  detail::MapState& state = *state_;
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  detail::ClosedGate closed(state.gate);
  state.window = window;
  state.window_keys.reset();
}

std::optional<MovingWindow> OccupancyMap::moving_window() const {
  detail::ReadLock lock(state_->gate);
  return state_->window;
}

WindowMove OccupancyMap::move_window(Vec3d position) {
  const Key key = grid_.key(position);  // throws std::out_of_range outside the map
  detail::MapState& state = *state_;
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  if (!state.window) throw std::logic_error("move_window: the map has no moving window (set_moving_window)");
  return detail::move_window_locked(state, grid_, key);
}

std::optional<VoxelBox> OccupancyMap::window_box() const {
  detail::ReadLock lock(state_->gate);
  if (!state_->window_keys) return std::nullopt;
  return VoxelBox{state_->window_keys->lo, state_->window_keys->hi};
}

}  // namespace umbra
