// Decay toward unknown: DecayRates, OccupancyMap's clock (set_decay,
// advance_clock) and the step the clock's advance applies to the tree
// (docs/design.md, "Decay toward unknown").
#include "map/map_decay.hpp"

#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/map/voxel_box.hpp"

namespace umbra {

void DecayRates::validate() const {
  const auto check = [](double rate, const char* name) {
    if (!(std::isfinite(rate) && rate >= 0.0)) {
      throw std::invalid_argument(std::string("decay rate ") + name + " must be finite and >= 0 (log-odds per second), got " +
                                  std::to_string(rate));
    }
  };
  check(occupied_per_second, "occupied_per_second");
  check(free_per_second, "free_per_second");
  if (region) region->validate();
}

namespace detail {

void advance_clock_locked(MapState& state, double time) {
  UMBRA_ASSERT(std::isfinite(time));
  if (state.clock && time <= *state.clock) return;  // a late scan: the clock never goes back
  // Readers read the clock too: it changes with the gate closed.
  ClosedGate closed(state.gate);
  if (!state.clock) {
    state.clock = time;  // the first time: nothing has aged yet
    return;
  }
  const double elapsed = time - *state.clock;
  state.clock = time;
  if (!state.decay.enabled()) return;
  // The step is rounded to float once, as the tree's values are; the rule
  // (and the brute force in the tests) applies this same float to each value.
  const OccupancyTree::DecayStep step{static_cast<float>(state.decay.occupied_per_second * elapsed),
                                      static_cast<float>(state.decay.free_per_second * elapsed)};
  if (!state.journal->active()) {
    state.tree.decay(step, state.decay_keys);
    return;
  }
  // A distance field listens: tell it the coarse nodes whose states changed.
  std::vector<OccupancyTree::DecayChange> changes;
  state.tree.decay(step, state.decay_keys, &changes, ChangeJournal::kJournalDepth);
  for (const OccupancyTree::DecayChange& change : changes) state.journal->record(change.code, change.depth);
}

}  // namespace detail

void OccupancyMap::set_decay(const DecayRates& rates) {
  rates.validate();
  std::optional<OccupancyTree::KeyBox> keys;
  if (rates.region) {
    const VoxelBox box = voxel_box(grid_, *rates.region);  // throws std::out_of_range wholly outside the map
    keys = OccupancyTree::KeyBox{box.lo, box.hi};
  }
  detail::MapState& state = *state_;
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  detail::ClosedGate closed(state.gate);
  state.decay = rates;
  state.decay_keys = keys;
}

DecayRates OccupancyMap::decay() const {
  detail::ReadLock lock(state_->gate);
  return state_->decay;
}

void OccupancyMap::advance_clock(double time) {
  if (!std::isfinite(time)) throw std::invalid_argument("clock time must be finite, got " + std::to_string(time));
  detail::MapState& state = *state_;
  if (state.gate.held_by_this_thread()) state.gate.close();  // throws: this thread is reading the map
  std::lock_guard writer(state.writer);
  detail::advance_clock_locked(state, time);
}

std::optional<double> OccupancyMap::clock() const {
  detail::ReadLock lock(state_->gate);
  return state_->clock;
}

}  // namespace umbra
