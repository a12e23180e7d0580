// FieldClearance: the explorer's ball and capsule checks answered from a
// distance field (umbra/field/distance_field.hpp) where it can, with the
// map's own check where it cannot, so the answer is always the map's.
//
// The field gives, for the voxel holding a point p, D = the distance from
// that voxel's centre c to the nearest blocking (occupied or unknown)
// voxel's cube, capped at max_distance. With e = |p - c|, the true distance
// from p to the nearest blocking cube lies in [D - e, D + e] (triangle
// inequality; only >= D - e when D is capped). A voxel belongs to a ball or
// capsule when its cube is within the radius (shapes.hpp), so:
//   ball (p, r):   free    when D - e > r,
//                  blocked when D + e <= r (and D not capped),
//                  otherwise the map's is_free(Sphere) decides.
//   capsule (a, b, r): walked from a to b; at a point p of the segment the
//                  lower bound D - e leaves a slack s = D - e - r, and every
//                  point within s of p is clear, so the walk steps on by s.
//                  Free when the walk reaches b; blocked when some p has a
//                  ball blocked as above; a slack below `min_step` (the
//                  segment grazes a surface) hands the capsule to the map's
//                  is_free(Capsule).
// A margin of 1e-6 m on every comparison keeps float rounding from deciding
// (such cases go to the map). So the decisions are exactly the map's
// (tests/explore/field_clearance_test.cpp checks it on the plant).
//
// Concurrency: update() on the mapping thread after each scan; the checks
// on the planning thread, concurrently (the field's contract: a check sees
// the field after some whole update, the map's check after some whole
// scan). Between a scan and the field's update the field is one scan behind
// the map: a check then answers for the map before that scan, as a check
// made a moment earlier would have.
//
// Cost: a ball check is one field query (~0.1-0.3 us) when it decides; a
// capsule one query per step (a few for a 1.5 m edge in open space). The
// field's update after each scan is the price (measured in docs/exploration.md).
#pragma once

#include <atomic>
#include <cstdint>

#include "umbra/field/distance_field.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::explore {

/// How often the field decided a check and how often the map had to.
struct ClearanceCounts {
  std::uint64_t balls_by_field = 0;
  std::uint64_t balls_by_map = 0;
  std::uint64_t capsules_by_field = 0;
  std::uint64_t capsules_by_map = 0;
  std::uint64_t field_queries = 0;  ///< distance() calls, both kinds
};

class FieldClearance {
 public:
  /// A field of `map` (which must outlive this) up to `max_distance` metres,
  /// kept over the whole known space. Throws std::invalid_argument for a
  /// max_distance the field refuses.
  FieldClearance(const OccupancyMap& map, double max_distance);

  /// Brings the field up to date with the map (after each scan).
  void update() { field_.update(); }

  /// What map.is_free(ball).free and map.is_free(path).free answer.
  [[nodiscard]] bool is_free(const Sphere& ball) const;
  [[nodiscard]] bool is_free(const Capsule& path) const;

  [[nodiscard]] ClearanceCounts counts() const;
  [[nodiscard]] std::size_t memory_bytes() const { return field_.memory_bytes(); }
  [[nodiscard]] const DistanceField& field() const { return field_; }

 private:
  enum class Verdict { free, blocked, unsure };
  /// What the field says of the ball (p, r); `slack` gets D - e - r (how far
  /// beyond the radius the nearest blocking cube is at least).
  Verdict ball(Vec3d p, double r, double& slack) const;

  const OccupancyMap& map_;
  DistanceField field_;
  double max_distance_;
  double min_step_;  ///< metres; a capsule walk with smaller steps goes to the map
  // Counted with relaxed atomics: checks are const and may come from any reader thread.
  mutable std::atomic<std::uint64_t> balls_by_field_{0};
  mutable std::atomic<std::uint64_t> balls_by_map_{0};
  mutable std::atomic<std::uint64_t> capsules_by_field_{0};
  mutable std::atomic<std::uint64_t> capsules_by_map_{0};
  mutable std::atomic<std::uint64_t> field_queries_{0};
};

}  // namespace umbra::explore
