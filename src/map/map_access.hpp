// MapAccess: how umbra's own code (queries, file readers and writers, tests)
// reaches the tree inside an OccupancyMap, always under the map's locks.
//
//   MapAccess::read(map, [&](const OccupancyTree& tree) { ... });   // a reader
//   MapAccess::build(map, [&](TreeBuilder& builder) { ... });       // a file reader filling a new map
//
// Not installed: users see only OccupancyMap's public functions.
#pragma once

#include <mutex>
#include <utility>

#include "map/map_state.hpp"
#include "tree/tree_builder.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::detail {

class MapAccess {
 public:
  /// Runs read(tree) holding the map for reading; returns what it returns.
  template <typename Read>
  static decltype(auto) read(const OccupancyMap& map, Read&& read) {
    ReadLock lock(map.state_->gate);
    return std::forward<Read>(read)(std::as_const(map.state_->tree));
  }

  /// Runs build(builder) with the map to itself, then recomputes every inner
  /// node and indicator from the leaves (TreeBuilder sets leaves only).
  template <typename Build>
  static void build(OccupancyMap& map, Build&& build) {
    std::lock_guard writer(map.state_->writer);
    ClosedGate closed(map.state_->gate);
    TreeBuilder builder(map.state_->tree);
    std::forward<Build>(build)(builder);
    builder.finish();
    map.state_->journal->record_everything();
  }

  /// The map's change journal (distance fields subscribe to it).
  static std::shared_ptr<ChangeJournal> journal(const OccupancyMap& map) { return map.state_->journal; }

  /// The gate, for a range that holds the map for reading across calls.
  static const ReadGate& gate(const OccupancyMap& map) { return map.state_->gate; }
  /// The tree without a lock: the caller holds gate(map) (a range), or the
  /// map is its own (tests).
  static const OccupancyTree& tree_unlocked(const OccupancyMap& map) { return map.state_->tree; }
};

}  // namespace umbra::detail
