// Integrator: turns one scan (sensor origin + points) into map updates.
//
// Semantics are OctoMap's insertPointCloud (DESIGN.md §1):
//  - simple:   a ray from the origin to every point; the voxels before the
//              end voxel get a miss, the end voxel a hit
//              (insertPointCloud(..., discretize = false));
//  - discrete: end points are first reduced to one per voxel and rays go to
//              the voxel centres (insertPointCloud(..., discretize = true)).
// Within one scan a voxel is updated at most once and a hit wins over a miss.
// A point farther than max_range (when max_range > 0) gives only a miss ray
// truncated at max_range. NaN / infinite points are skipped and counted; so
// are points outside the map (OctoMap drops their rays too). With colours,
// every point that gives a hit adds its colour to its voxel (for the discrete
// integrator: every point of an end voxel whose ray gives a hit).
//
// Data flow: points -> ray walk -> UpdateBatch (de-duplicated hit/miss
// marks, no hashing) -> OccupancyTree::apply (one walk over the tree). The
// batch is kept between scans only as a member to avoid re-creating it; its
// memory is released after every scan so that the peak while inserting stays
// close to the map itself.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "umbra/core/grid.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/tree/occupancy_tree.hpp"
#include "umbra/tree/update_batch.hpp"

namespace umbra {

enum class IntegratorKind { simple, discrete };

/// "simple" / "discrete"; throws std::invalid_argument for anything else.
IntegratorKind parse_integrator_kind(const std::string& name);
const char* to_string(IntegratorKind kind);

struct InsertOptions {
  IntegratorKind integrator = IntegratorKind::simple;
  /// Metres; <= 0 means unlimited (OctoMap's default -1).
  double max_range = -1.0;

  /// Throws std::invalid_argument when max_range is NaN.
  void validate() const;
};

/// What happened to the points of one scan.
struct InsertStats {
  std::size_t points = 0;          ///< points given
  std::size_t rays = 0;            ///< rays traced (after per-voxel de-duplication when discrete)
  std::size_t hits = 0;            ///< end points that were marked occupied
  std::size_t truncated = 0;       ///< rays beyond max_range, cut there, without a hit
  std::size_t non_finite = 0;      ///< NaN / infinite points, skipped
  std::size_t out_of_bounds = 0;   ///< points (or truncated ends) outside the map, skipped

  InsertStats& operator+=(const InsertStats& other);
};

class Integrator {
 public:
  /// Integrates one scan into `tree`, whose voxels are laid out by `grid`.
  /// `colors` is empty or holds one colour per point (the tree must have
  /// colour then): every point that gives a hit adds its colour to its voxel.
  /// Throws std::invalid_argument for a non-finite origin and
  /// std::out_of_range for an origin outside the map; the tree is unchanged then.
  InsertStats insert(OccupancyTree& tree, const Grid& grid, const SensorModel& sensor, Vec3f origin,
                     std::span<const Vec3f> points, std::span<const Rgb> colors, const InsertOptions& options);

  /// Bytes held between scans: the empty batch and the longest ray's runs.
  [[nodiscard]] std::size_t memory_bytes() const {
    return batch_.memory_bytes() + runs_.capacity() * sizeof(BrickRun);
  }

 private:
  /// Adds the rays to `points` to the batch; the shared part of both integrators.
  void trace(const Grid& grid, Vec3f origin, std::span<const Vec3f> points, double max_range,
             InsertStats& stats);
  /// Walks one ray and adds its misses to the batch, a brick at a time.
  void add_ray_misses(const Grid& grid, Vec3f origin, Key origin_key, Vec3f end, Key end_key);

  /// A run of a ray's voxels inside one brick (4x4x4 voxels, see UpdateBatch):
  /// bit i of `voxels` is voxel (code & ~63) + i.
  struct BrickRun {
    std::uint64_t code;
    std::uint64_t voxels;
  };

  UpdateBatch batch_;
  std::vector<BrickRun> runs_;  // one ray's runs; capacity kept between rays
};

}  // namespace umbra
