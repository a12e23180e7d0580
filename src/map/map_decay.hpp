// The map's clock and its decay toward unknown, for the map's own code
// (OccupancyMap::advance_clock and the stamped inserts of occupancy_map.cpp).
#pragma once

#include "map/map_state.hpp"

namespace umbra::detail {

/// Advances `state`'s clock to `time` (finite) and applies the decay of the
/// time passed, in one exclusive phase (it closes the gate itself, only when
/// something may change). The caller holds state.writer. With `pool`, the
/// step runs on its threads (the same map, bit for bit).
void advance_clock_locked(MapState& state, double time, ThreadPool* pool = nullptr);

/// Folds what the current rates accumulated up to the clock into
/// state.decay_totals, before the rates change (nothing without a clock).
void restart_decay_totals(MapState& state);

}  // namespace umbra::detail
