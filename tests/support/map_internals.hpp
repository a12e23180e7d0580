// Test access to a map's internals (the tree and its invariants), through
// the same private accessor umbra's own code uses.
#pragma once

#include <string>

#include "map/map_access.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

/// The map's tree, for a test that owns the map (no other thread uses it).
inline const OccupancyTree& tree_of(const OccupancyMap& map) { return detail::MapAccess::tree_unlocked(map); }

/// Empty when every invariant of the map's tree holds, else the first violation.
inline std::string check_invariants(const OccupancyMap& map) {
  return detail::MapAccess::read(map, [](const OccupancyTree& tree) { return tree.check_invariants(); });
}

/// The map's thresholds in log-odds, as the tree compares them.
inline LogOddsThresholds log_odds_thresholds(const OccupancyMap& map) {
  return LogOddsThresholds::from(map.thresholds());
}

}  // namespace umbra::test
