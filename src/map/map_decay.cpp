// Decay toward unknown: DecayRates, OccupancyMap's clock (set_decay,
// advance_clock) and the step the clock's advance applies to the tree
// (docs/design.md, "Decay toward unknown").
#include "map/map_decay.hpp"

#include <algorithm>
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

namespace {

/// Decay amounts are whole multiples of this many log-odds (2^-16): a float
/// value below 256 in magnitude minus such a multiple is exact in single
/// precision, so two steps take off exactly what one step over the same
/// time does (the rule in docs/design.md, "Decay toward unknown"), and a
/// pending amount could be applied later in one go with the same result.
constexpr double kDecayQuantum = 1.0 / 65536.0;

/// What one side (occupied or free) of a step from `previous` to `time`
/// takes off: the difference of the amounts accumulated up to the two
/// times, each rounded down to whole quanta. Exact in double (whole numbers
/// of quanta, a power of two) and in float below 256 log-odds; a larger step
/// takes every value to 0 anyway (capped to stay a float; NaN, from absurd
/// rates or times that overflow, also counts as everything).
float step_amount(double rate, double total, double since, double previous, double time) {
  if (rate == 0.0) return 0.0f;
  const double quanta = std::floor((total + rate * (time - since)) / kDecayQuantum) -
                        std::floor((total + rate * (previous - since)) / kDecayQuantum);
  return quanta >= 0.0 ? static_cast<float>(std::min(quanta * kDecayQuantum, 1e30)) : 1e30f;
}

}  // namespace

void restart_decay_totals(MapState& state) {
  if (!state.clock) return;  // they start with the clock
  const double elapsed = *state.clock - state.decay_totals.since;
  state.decay_totals = {*state.clock, state.decay_totals.occupied + state.decay.occupied_per_second * elapsed,
                        state.decay_totals.free + state.decay.free_per_second * elapsed};
}

void advance_clock_locked(MapState& state, double time, ThreadPool* pool) {
  UMBRA_ASSERT(std::isfinite(time));
  if (state.clock && time <= *state.clock) return;  // a late scan: the clock never goes back
  // Readers read the clock too: it changes with the gate closed.
  ClosedGate closed(state.gate);
  if (!state.clock) {
    state.clock = time;  // the first time: nothing has aged yet
    state.decay_totals = {time, 0.0, 0.0};
    return;
  }
  const double previous = *state.clock;
  state.clock = time;
  if (!state.decay.enabled()) return;
  const DecayTotals& totals = state.decay_totals;
  const OccupancyTree::DecayStep step{
      step_amount(state.decay.occupied_per_second, totals.occupied, totals.since, previous, time),
      step_amount(state.decay.free_per_second, totals.free, totals.since, previous, time)};
  if (!state.journal->active()) {
    state.tree.decay(step, state.decay_keys, nullptr, 0, pool);
    return;
  }
  // A distance field listens: tell it the coarse nodes whose states changed.
  std::vector<OccupancyTree::DecayChange> changes;
  state.tree.decay(step, state.decay_keys, &changes, ChangeJournal::kJournalDepth, pool);
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
  detail::restart_decay_totals(state);  // what the old rates accumulated up to now
  state.decay = rates;
  state.decay_keys = keys;
  // The groups' event bounds, once (a walk of the map), so that the steps
  // cost only the nodes whose state they change (docs/design.md, Cost).
  if (rates.enabled() && !keys) state.tree.track_decay();
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
