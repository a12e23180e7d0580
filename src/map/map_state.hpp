// MapState: what an OccupancyMap holds behind its public face.
//
// The tree, the integrator and the settings, with the two locks of the
// concurrency contract (occupancy_map.hpp): `writer` lets one writer in at a
// time (inserting, or any other change), and `gate` keeps readers out only
// while the tree itself changes. A reader holds `gate`; a writer holds
// `writer` throughout and closes `gate` for its exclusive phase.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <optional>

#include "integrate/integrator.hpp"
#include "core/read_gate.hpp"
#include "map/change_journal.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/map/decay.hpp"
#include "umbra/map/moving_window.hpp"

namespace umbra::detail {

/// The decay the clock has accumulated since it started, in log-odds
/// (docs/design.md, "Decay toward unknown"): at clock time t >= `since`,
/// `occupied + rates.occupied_per_second * (t - since)` for positive values
/// and likewise for negative ones. `since` moves (and the amounts with it)
/// only when the rates change, so the amount up to a time does not depend
/// on how the clock got there.
struct DecayTotals {
  double since = 0.0;
  double occupied = 0.0;
  double free = 0.0;
};

struct MapState {
  MapState(int depth_levels, const SensorModel& sensor_model, const Thresholds& occupancy_thresholds, bool color)
      : sensor(sensor_model),
        thresholds(occupancy_thresholds),
        tree(depth_levels, LogOddsRange::from(sensor_model), LogOddsThresholds::from(occupancy_thresholds), color) {}

  SensorModel sensor;
  Thresholds thresholds;
  OccupancyTree tree;
  Integrator integrator;
  /// integrator.memory_bytes() after the last scan: the integrator changes
  /// while readers run (tracing), so readers see only this copy.
  std::atomic<std::size_t> integrator_bytes{0};
  std::optional<Aabb> bounding_box;
  /// What changed, for distance fields (change_journal.hpp); shared so that
  /// a field outliving this state (the map was assigned) still holds it.
  std::shared_ptr<ChangeJournal> journal = std::make_shared<ChangeJournal>();
  // Decay toward unknown (map_decay.cpp): the rates, their region as keys,
  // the clock (nothing until the first time is given) and the decay it has
  // accumulated (the amounts each step applies are differences of these).
  DecayRates decay;
  std::optional<OccupancyTree::KeyBox> decay_keys;
  std::optional<double> clock;
  DecayTotals decay_totals;
  // A map that moves (map_window.cpp): the window's settings, and its box
  // as keys once it has been placed (nothing before the first move).
  std::optional<MovingWindow> window;
  std::optional<OccupancyTree::KeyBox> window_keys;
  std::mutex writer;
  ReadGate gate;
};

}  // namespace umbra::detail
