// Integrator: turns one scan (sensor origin + points) into map updates.
//
// Semantics of the simple and discrete integrators are OctoMap's
// insertPointCloud (docs/design.md, Semantics), voxel for voxel:
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
// The fast integrator (the UFOMap paper's "fast discrete", with one ray per
// end voxel to the first point that fell in it): free space is cleared a
// depth-`clear_depth` node at a time where nothing forbids it, and voxel by
// voxel along each ray elsewhere: in nodes the map says hold an obstacle, in
// nodes that hold or touch a hit of this scan, and over the last
// `fine_steps` nodes before the end node and the end node itself. So every
// ray updates the voxels it really crosses near surfaces, as the simple
// integrator on those points does (with enough fine steps it is exactly
// that). Hits are always at the finest depth.
//
// Bounding box (OccupancyMap::set_bounding_box): rays are clipped to it
// (begin and end move towards each other; a clipped end gives no hit), and
// only voxels in the box change; points outside still clear space inside.
//
// Colors: every point that gives a hit adds its color to its voxel (for the
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
#include "umbra/core/function_ref.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/log_odds.hpp"
#include "core/thread_pool.hpp"
#include "umbra/core/vec3.hpp"
#include "integrate/image_points.hpp"
#include "integrate/scan_images.hpp"
#include "integrate/projective_frame.hpp"
#include "integrate/ray_tracer.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/integrate/depth_image.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra {

class Integrator {
 public:
  Integrator();
  ~Integrator();
  Integrator(Integrator&&) noexcept;
  Integrator& operator=(Integrator&&) noexcept;

  /// Traces one scan against `tree` (which it only reads: queries may run
  /// meanwhile) into the pending update; apply() then writes it. `colors` is
  /// empty or holds one color per point (the tree must have color then).
  /// `box`: clip rays to it. Throws std::invalid_argument for a non-finite
  /// origin or bad options and std::out_of_range for an origin outside the
  /// map; nothing is pending then.
  InsertStats trace(const OccupancyTree& tree, const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                    std::span<const Rgb> colors, const InsertOptions& options,
                    const std::optional<Aabb>& box = std::nullopt);
  /// The same for a depth image taken from `pose` (camera to map) with
  /// `camera`; `colors` is empty or holds one color per pixel. The
  /// projective integrator takes its misses from the image
  /// (projective_tracer.hpp) and its hits from the image's points, as the
  /// discrete integrator would; the other integrators get the points
  /// (back_project). Throws as trace(), and std::invalid_argument for bad
  /// intrinsics, a pose that is not rigid or a color count that is not the
  /// pixel count.
  InsertStats trace_image(const OccupancyTree& tree, const Grid& grid, const DepthImage& image,
                          const PinholeCamera& camera, const Pose& pose, std::span<const Rgb> colors,
                          const InsertOptions& options, const std::optional<Aabb>& box = std::nullopt);
  /// Writes the pending update of the last trace() into `tree` (the same
  /// tree, unchanged since) and forgets it.
  void apply(OccupancyTree& tree, const SensorModel& sensor);
  /// The update apply() will write (between trace() and apply()): one batch,
  /// or one per worker (the projective integrator's, applied side by side
  /// without a merge: OccupancyTree::apply of several batches).
  [[nodiscard]] std::vector<const UpdateBatch*> pending_batches() const;
  /// Forgets the pending update (after a failed trace).
  void discard();

  /// The thread pool for `threads` threads (0: all cores), as trace() uses
  /// it (started when needed); null for one thread. For work beside a scan
  /// on the same threads (a decay step before a stamped scan).
  ThreadPool* workers(unsigned threads);

  /// Bytes held between scans: the tracers' scratch buffers and empty batches.
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  void ensure_workers(unsigned threads);
  /// Color samples of the end voxels, as the discrete integrator takes
  /// them, for the next apply (on this thread). `codes`: the points' voxel
  /// codes, or empty.
  void queue_end_voxel_colors(const Grid& grid, Vec3f origin, std::span<const Vec3f> points, std::span<const Rgb> colors,
                              std::span<const std::uint64_t> codes, const InsertOptions& options,
                              const std::optional<KeyBox>& box_keys);
  /// trace() with the projective integrator: the scan as the six faces of
  /// images around its origin (scan_images.hpp).
  InsertStats trace_scan_projective(const OccupancyTree& tree, const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                    std::span<const Rgb> colors, const InsertOptions& options,
                                    const std::optional<Aabb>& box);
  /// Adds the hits whose voxel codes lie in [first, end) to a batch, counting them in the stats.
  using HitsInRange = FunctionRef<void(std::uint64_t first, std::uint64_t end, UpdateBatch&, InsertStats&)>;
  /// The projective integrator's misses for `frames`, into the tracers'
  /// batches (one per worker, all pending: no merge); with `tree`, its
  /// obstacles are cleared only where the frames' rays cross them.
  /// side_job(0 .. side_jobs - 1, a batch) run first, each on one worker
  /// while the others trace (the hits, into that worker's batch, and the
  /// colors). With `hits_in` (one frame only), side job 0 is not run on
  /// several threads: each subtree task adds the hits inside it to its own
  /// batch after its misses, and side job 0's place takes the hits outside
  /// every task (counted into `hit_stats`), so that the batches meet only
  /// above the tasks (tree/apply_batches.cpp).
  void trace_projective_misses(const OccupancyTree* tree, const Grid& grid, const InsertOptions& options,
                               const std::optional<KeyBox>& box_keys, std::span<const ProjectiveFrame> frames,
                               unsigned threads, std::size_t side_jobs,
                               FunctionRef<void(std::size_t, UpdateBatch&)> side_job,
                               const HitsInRange* hits_in = nullptr, InsertStats* hit_stats = nullptr);

  std::unique_ptr<ThreadPool> pool_;
  std::vector<std::unique_ptr<RayTracer>> tracers_;  // one per worker
  // Pending between trace() and apply(): the batches of tracers_[0 ..
  // pending_batches_) (one when merged into tracers_[0]'s).
  unsigned pending_threads_ = 0;  // 0: nothing pending
  unsigned pending_batches_ = 0;
  std::vector<OccupancyTree::ColorSample> pending_colors_;
  // The projective integrator's image and the points of the last depth
  // image, kept between scans (their buffers are reused).
  ProjectiveFrame frame_;
  // The surface band's image of the last depth image, reused by the next (SurfaceBand::make).
  std::shared_ptr<SurfaceBand::Image> band_image_;
  ScanImages scan_images_;
  ImagePoints image_points_;
};

}  // namespace umbra
