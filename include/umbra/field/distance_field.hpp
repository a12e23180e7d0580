// DistanceField: how far the nearest occupied voxel is, and separately the
// nearest unknown one, from any point of a map, and in which direction,
// kept up to date scan by scan.
//
//   umbra::DistanceField field(map, {.max_distance = 1.0});
//   map.insert_point_cloud(origin, points);
//   field.update();                                  // only where the scan changed the map
//   double clearance = field.distance({1.0, 2.0, 0.5});          // to the nearest blocking voxel
//   umbra::DistanceSample s = field.distance_and_gradient({1.0, 2.0, 0.5});
//
// What a distance is (docs/design.md, "Distance field"): a query point
// stands for the finest voxel holding it. At depth 0 the distance is from
// that voxel's centre to the nearest cube of an occupied (resp. unknown)
// voxel, 0 when the voxel itself is one, and capped at max_distance. So a
// sphere centred on a voxel centre is free (OccupancyMap::is_free) iff its
// radius is below min(occupied, unknown), the "blocking" distance. At depth
// d > 0 the cells are depth-d nodes and the sites the depth-d nodes holding
// an occupied (resp. unknown) voxel; the distance is from the nearest of the
// cell's voxel centres to the nearest such node's cube: never larger than
// the depth-0 distance of any voxel of the cell (conservative), and a sphere
// centred on a voxel centre is free at depth d when its radius is below it.
//
// Where it is kept: inside a box (like dynamicEDT3D; sites outside the box
// are not seen, a query outside it throws std::out_of_range), or, without a
// box, everywhere: the bricks of 8^3 cells holding known space and those
// within max_distance of them are stored; every other cell is unknown and
// has no occupied voxel within max_distance.
//
// Updates: update() reads the map's change journal (which nodes the scans
// since the last update touched) and re-reads those bricks. Within
// max_distance of the cells whose state changed, a brick none of whose
// cells lost its nearest site is lowered by the added sites alone (an exact
// minimum); one where some cell did is transformed again.
// Threshold or sensor-model changes, clear() and loading make it start over.
//
// Concurrency: queries (const functions) run concurrently with each other
// and with update(); each query sees the field after some whole update,
// never half of one (update() computes aside and swaps in one short
// exclusive phase). update() reads the map as a query does, so it runs
// concurrently with the map's readers and waits only for a scan's apply
// phase. The map must outlive the field and stay where it is.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

#include "umbra/core/aabb.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

class OccupancyMap;

struct DistanceFieldOptions {
  /// Metres; distances are capped here (> 0). The cost of building and
  /// updating grows with it (the window each cell looks through).
  double max_distance = 1.0;
  /// Depth of the cells (0: finest voxels); see the file comment.
  int depth = 0;
  /// Keep the field inside this box only (nothing: the whole known space).
  std::optional<Aabb> box;
  /// Threads that build and update the field (chunks of bricks in
  /// parallel); 0: all hardware threads. Queries always run on the caller.
  unsigned threads = 1;

  /// Throws std::invalid_argument naming the bad value.
  void validate() const;
};

struct DistanceSample {
  double occupied = 0.0;  ///< metres to the nearest occupied voxel, capped at max_distance
  double unknown = 0.0;   ///< metres to the nearest unknown voxel, capped at max_distance
  /// Unit vector pointing away from the nearest blocking voxel (the
  /// occupied one on a tie); zero when the cell itself blocks or nothing
  /// blocks within max_distance.
  Vec3d gradient;
  [[nodiscard]] double blocking() const { return occupied < unknown ? occupied : unknown; }
};

/// Sizes of a field, for memory reports and benchmarks.
struct DistanceFieldStats {
  std::size_t bricks = 0;        ///< bricks of 8^3 cells stored
  std::size_t memory_bytes = 0;  ///< everything the field allocated
  std::size_t bricks_recomputed = 0;  ///< by the last build or update (transformed or lowered)
  /// Of those, the bricks the last build or update ran the full transform
  /// on (the rest were lowered by added sites only; see update()).
  std::size_t bricks_transformed = 0;
  std::size_t bricks_reread = 0;      ///< bricks whose sites the last build or update read from the map
};

class DistanceField {
 public:
  /// Builds the field of `map` (which must outlive it). Throws
  /// std::invalid_argument for bad options (a depth beyond the map's
  /// depth_levels() - 3, a max_distance of more than 120 cells).
  DistanceField(const OccupancyMap& map, const DistanceFieldOptions& options = {});
  ~DistanceField();
  DistanceField(const DistanceField&) = delete;
  DistanceField& operator=(const DistanceField&) = delete;

  /// Brings the field up to date with the map, recomputing only around the
  /// cells whose state changed since the last build or update.
  void update();
  /// Moves the box (nothing: the whole known space) and rebuilds.
  void set_box(const std::optional<Aabb>& box);
  /// Recomputes everything.
  void rebuild();

  [[nodiscard]] const DistanceFieldOptions& options() const;

  /// Distance to the nearest blocking (occupied or unknown) voxel, capped.
  /// Throws std::out_of_range for a point outside the map, or outside the box.
  [[nodiscard]] double distance(Vec3d point) const;
  [[nodiscard]] DistanceSample distance_and_gradient(Vec3d point) const;
  /// Many at once (sizes must match; std::invalid_argument otherwise). The
  /// field is held for reading a chunk at a time. A bad point throws
  /// std::out_of_range naming its index; the answers before it are written.
  void distance(std::span<const Vec3d> points, std::span<double> out) const;
  void distance_and_gradient(std::span<const Vec3d> points, std::span<DistanceSample> out) const;

  [[nodiscard]] DistanceFieldStats stats() const;
  [[nodiscard]] std::size_t memory_bytes() const { return stats().memory_bytes; }

  struct State;

 private:
  std::unique_ptr<State> state_;
};

}  // namespace umbra
