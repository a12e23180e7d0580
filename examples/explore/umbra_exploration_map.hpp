// The explorer's map on umbra: an OccupancyMap asked through its public API
// only, with no lock of ours (the map's concurrency contract lets the
// planning thread query while the mapping thread inserts).
//
//   collision of a node:  map.is_free(Sphere)             unknown blocks
//   collision of an edge: map.is_free(Capsule)            every voxel within the radius of the segment
//     (or both from a distance field kept after every scan, the map's
//      check only where the field cannot decide: field_clearance.hpp,
//      UmbraMapOptions::clearance)
//   gain of a view:       map.information_gain(Frustum)   exact, or fast (one ray per 2^d-voxel node)
//   inserting an image:   map.insert_point_cloud(...)     the fast integrator, one thread
//   coverage:             map.query(leaf && free)
#pragma once

#include <memory>

#include "exploration_map.hpp"
#include "field_clearance.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/information_gain.hpp"

namespace umbra::explore {

/// Where the planner's ball and capsule checks get their answer.
enum class ClearanceSource {
  collision_checks,  ///< the map's is_free(Sphere) / is_free(Capsule)
  distance_field,    ///< a DistanceField updated after every scan (same answers; field_clearance.hpp)
};

struct UmbraMapOptions {
  double resolution = 0.16;
  IntegratorKind integrator = IntegratorKind::fast;
  GainMethod gain = GainMethod::exact;
  int fast_gain_depth = 2;  ///< GainOptions::fast_depth
  /// The map's checks by default: in the study the field's updates cost
  /// more than its faster checks save (docs/exploration.md, "Clearance
  /// from a distance field").
  ClearanceSource clearance = ClearanceSource::collision_checks;
  /// Metres, the field's max_distance (distance_field only): a check can
  /// be decided by the field only when this exceeds its radius plus half a
  /// voxel's diagonal; larger lets capsule walks take longer steps but
  /// makes updates dearer.
  double field_max_distance = 1.0;
  /// > 0: a map that moves, keeping a box of at least this many metres
  /// around each frame's origin (MovingWindow; what leaves is dropped).
  double window_half_extent = 0.0;
};

class UmbraExplorationMap final : public ExplorationMap {
 public:
  explicit UmbraExplorationMap(const UmbraMapOptions& options);

  [[nodiscard]] std::string name() const override { return "umbra"; }
  [[nodiscard]] double resolution() const override { return map_.resolution(); }
  void assume_free(const Sphere& ball) override;
  void insert(Vec3f origin, std::span<const Vec3f> points, double max_range) override;
  [[nodiscard]] bool is_free(const Sphere& ball) const override;
  [[nodiscard]] bool is_free(const Capsule& path) const override;
  [[nodiscard]] double gain(const Frustum& view) const override;
  void for_each_free_node(FunctionRef<void(Vec3d min, Vec3d max)> visit) const override;
  /// The map's bytes, and the field's when there is one.
  [[nodiscard]] std::size_t memory_bytes() const override;

  /// The map itself (to save or show it when exploring is over).
  [[nodiscard]] const OccupancyMap& map() const { return map_; }
  /// Seconds inserting kept queries out (InsertStats::exclusive_seconds), summed.
  [[nodiscard]] double exclusive_seconds() const { return exclusive_seconds_; }
  /// The distance field's clearance checks (null with collision_checks).
  [[nodiscard]] const FieldClearance* field_clearance() const { return clearance_.get(); }
  /// CPU seconds insert() spent updating the field, summed (mapping thread; 0 without a field).
  [[nodiscard]] double field_update_seconds() const { return field_update_seconds_; }

 private:
  OccupancyMap map_;
  InsertOptions insert_options_;
  GainOptions gain_options_;
  double exclusive_seconds_ = 0.0;  ///< written by the mapping thread only
  std::unique_ptr<FieldClearance> clearance_;  ///< with ClearanceSource::distance_field
  double field_update_seconds_ = 0.0;          ///< written by the mapping thread only
};

}  // namespace umbra::explore
