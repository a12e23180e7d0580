// Integrator: turns one scan (sensor origin + points) into map updates.
//
// Semantics of the simple and discrete integrators are OctoMap's
// insertPointCloud (DESIGN.md §1), voxel for voxel:
//  - simple:   a ray from the origin to every point; the voxels before the
//              end voxel get a miss, the end voxel a hit
//              (insertPointCloud(..., discretize = false));
//  - discrete: end points are first reduced to one per voxel and rays go to
//              the voxel centres (insertPointCloud(..., discretize = true)).
// Within one scan a voxel is updated at most once and a hit wins over a miss.
// A point farther than max_range (when max_range > 0) gives only a miss ray
// truncated at max_range. NaN / infinite points are skipped and counted; so
// are points outside the map (OctoMap drops their rays too).
//
// The fast integrator (the UFOMap paper's "fast discrete"): end points as for
// discrete; free space is cleared a depth-`clear_depth` node at a time, and
// only the last `fine_steps` coarse nodes before the end point (and the end
// node) are traced voxel by voxel; `fine_steps = 0` clears coarse nodes only.
// A coarse node the map says holds an obstacle, or that holds a hit of this
// scan, is never cleared whole: the ray is traced through it voxel by voxel.
// Hits are always at the finest depth.
//
// Bounding box (OccupancyMap::set_bounding_box): rays are clipped to it
// (begin and end move towards each other; a clipped end gives no hit), and
// only voxels in the box change; points outside still clear space inside.
//
// Colours: every point that gives a hit adds its colour to its voxel (for the
// discrete and fast integrators: every point of an end voxel whose ray gives
// a hit).
//
// Threads: the rays are split over a thread pool, each worker tracing into
// its own UpdateBatch; the batches are merged and applied once. The map is
// the same for every thread count (a test checks it).
//
// Data flow: points -> ray walk -> UpdateBatch (de-duplicated hit/miss
// marks, no hashing) -> OccupancyTree::apply (one walk over the tree). The
// batches' memory is released after every scan so that the peak while
// inserting stays close to the map itself.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "umbra/core/aabb.hpp"
#include "umbra/core/color.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/thread_pool.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/ray_tracer.hpp"
#include "umbra/tree/occupancy_tree.hpp"

namespace umbra {

enum class IntegratorKind { simple, discrete, fast };

/// "simple" / "discrete" / "fast"; throws std::invalid_argument for anything else.
IntegratorKind parse_integrator_kind(const std::string& name);
const char* to_string(IntegratorKind kind);

struct InsertOptions {
  IntegratorKind integrator = IntegratorKind::simple;
  /// Metres; <= 0 means unlimited (OctoMap's default -1).
  double max_range = -1.0;
  /// fast: depth of the nodes cleared whole; -1: the depth whose nodes are
  /// closest to 16 cm (the UFOMap paper's setting). At depth 0 the fast
  /// integrator is the discrete one.
  int clear_depth = -1;
  /// fast: coarse nodes before the end point traced voxel by voxel; 0: none.
  int fine_steps = 2;
  /// Threads tracing rays; 0: all cores.
  unsigned threads = 0;

  /// Throws std::invalid_argument naming the bad field (NaN max_range,
  /// clear_depth above the map's depth levels, negative fine_steps).
  void validate(int depth_levels) const;
  /// The clear depth used for a map with this grid.
  [[nodiscard]] int resolved_clear_depth(const Grid& grid) const;
};

/// What happened to the points of one scan.
struct InsertStats {
  std::size_t points = 0;          ///< points given
  std::size_t rays = 0;            ///< rays traced (after per-voxel de-duplication when discrete / fast)
  std::size_t hits = 0;            ///< rays whose end voxel got a hit
  std::size_t truncated = 0;       ///< rays beyond max_range, cut there, without a hit
  std::size_t non_finite = 0;      ///< NaN / infinite points, skipped
  std::size_t out_of_bounds = 0;   ///< points (or truncated ends) outside the map, skipped
  std::size_t outside_box = 0;     ///< rays that miss the bounding box entirely, skipped

  InsertStats& operator+=(const InsertStats& other);
};

class Integrator {
 public:
  Integrator();
  ~Integrator();
  Integrator(Integrator&&) noexcept;
  Integrator& operator=(Integrator&&) noexcept;

  /// Integrates one scan into `tree`, whose voxels are laid out by `grid`.
  /// `colors` is empty or holds one colour per point (the tree must have
  /// colour then). `box`: clip rays to it. Throws std::invalid_argument for
  /// a non-finite origin or bad options and std::out_of_range for an origin
  /// outside the map; the tree is unchanged then.
  InsertStats insert(OccupancyTree& tree, const Grid& grid, const SensorModel& sensor, Vec3f origin,
                     std::span<const Vec3f> points, std::span<const Rgb> colors, const InsertOptions& options,
                     const std::optional<Aabb>& box = std::nullopt);

  /// Bytes held between scans: the tracers' scratch buffers and empty batches.
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  void ensure_workers(unsigned threads);

  std::unique_ptr<ThreadPool> pool_;
  std::vector<std::unique_ptr<RayTracer>> tracers_;  // one per worker
};

}  // namespace umbra
