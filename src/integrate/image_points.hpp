// ImagePoints: a depth image's points, their voxels and the voxels they hit,
// found in bands of rows on every worker.
//
// A depth image's points are needed by every integrator (as a point cloud)
// and by the projective integrator for its hits (the voxels holding a
// point, each once) and colors. Done on one thread this front end was a
// third of a TUM frame's insertion at 2 cm and capped two threads at 1.2x
// one on a 16-core machine, so the image is cut into bands of rows, each
// band back-projected, its points' voxel codes computed and its candidate
// hit voxels gathered on its own worker, written straight into the
// image-wide arrays (a first pass counts each band's readings), and its
// voxels sorted there too. The result does not depend on the number of
// bands: the points come in pixel order, and the voxels are visited in code
// order, each once.
//
// back_project_rows is the one back-projection of the library: the public
// back_project (umbra/map/depth_image.hpp) calls it for all rows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/function_ref.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/depth_image.hpp"
#include "core/radix_sort.hpp"
#include "integrate/brick_hits.hpp"

namespace umbra {

class ThreadPool;

/// The pixels of rows [row_begin, row_end) with a reading.
std::size_t count_readings(const DepthImage& depth, int row_begin, int row_end);

/// The map points of the pixels of rows [row_begin, row_end) with a reading,
/// in pixel order, written from `points` on (and their pixel indices from
/// `pixels` on, when not null): z = depth, x = (u - cx) z / fx,
/// y = (v - cy) z / fy, in double, then pose.apply. `points` has room for
/// count_readings() of those rows. Returns how many it wrote.
std::size_t back_project_rows(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose, int row_begin,
                              int row_end, Vec3f* points, std::uint32_t* pixels);

class ImagePoints {
 public:
  /// Finds the points of `depth` (as back_project gives them), their voxel
  /// codes, their colors (one per point, from `colors`: empty or one per
  /// pixel) and the voxels they fall in; on `pool`'s workers when given.
  /// `alongside` runs on one worker meanwhile (work that needs the image but
  /// not its points).
  /// With `voxels_only` (and no colors) only the voxels and the counts are
  /// kept: points(), pixels() and codes() stay empty. The projective
  /// integrator needs no more, and the image-wide arrays were a counting
  /// pass over the image and 4.8 MB of fresh memory for a Kinect frame
  /// (its page faults were 1,200 of a fresh map's first frame's 2,400).
  void build(const Grid& grid, const DepthImage& depth, const PinholeCamera& camera, const Pose& pose,
             std::span<const Rgb> colors, ThreadPool* pool, FunctionRef<void()> alongside,
             bool voxels_only = false);

  /// After a voxels_only build: back-projects the whole image into points()
  /// and pixels() after all (on the calling thread; nothing to do when they
  /// were kept). For the surface band's rays, which only some frames need.
  void keep_points(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose);

  [[nodiscard]] std::span<const Vec3f> points() const { return points_; }
  [[nodiscard]] std::span<const std::uint32_t> pixels() const { return pixels_; }
  [[nodiscard]] std::span<const Rgb> colors() const { return colors_; }
  /// Each point's voxel code (kNonFiniteCode, kOutsideCode: none) when
  /// colors were given (for their samples), else empty.
  [[nodiscard]] std::span<const std::uint64_t> codes() const { return codes_; }
  /// Calls visit(code) for each voxel that holds a point, in increasing
  /// code order, each once (a merge of the bands' sorted voxels: run it
  /// alongside other work, it is serial).
  void for_each_voxel(FunctionRef<void(std::uint64_t)> visit) const;
  /// The same for the voxels whose codes lie in [first, end) (a subtree's, for its worker).
  void for_each_voxel_in(std::uint64_t first, std::uint64_t end, FunctionRef<void(std::uint64_t)> visit) const;
  /// The same voxels a brick at a time: visit(bricks) in increasing brick
  /// order, each brick's voxels in [first, end) that hold a point. A brick
  /// that several bands hold is visited once for each, one after another.
  void for_each_brick_in(std::uint64_t first, std::uint64_t end, FunctionRef<void(BrickVoxels)> visit) const;
  [[nodiscard]] std::size_t non_finite() const { return non_finite_; }
  [[nodiscard]] std::size_t out_of_bounds() const { return out_of_bounds_; }

  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  struct Band {
    int row_begin = 0;
    int row_end = 0;
    std::size_t first = 0;  // its first point in points_
    std::size_t count = 0;
    // Its voxels by brick: sorted, each brick once. A brick of 4x4x4
    // voxels holds about 17 of a TUM frame's voxels at 2 cm, and a row's
    // candidates mostly come a few to a brick: kept as bricks, a frame's
    // sort moves about 3 times fewer records than as voxel codes.
    std::vector<BrickVoxels> candidates;
    std::vector<std::uint64_t> above;  // the code last seen in each column
    RadixSortScratch<BrickVoxels> sort_scratch;
    std::size_t non_finite = 0;
    std::size_t out_of_bounds = 0;
    // voxels_only: one row's x factors, points and codes at a time (kept between images).
    std::vector<double> row_factors;
    std::vector<Vec3f> row_points;
    std::vector<std::uint64_t> row_codes;
  };
  /// Where find_voxels stands in its band's pixels (carried from one run of
  /// points to the next).
  struct VoxelScan {
    std::uint64_t left;        // the previous point's code
    std::uint32_t left_pixel;  // and pixel
    std::uint32_t row_start;   // the first pixel of the row of the previous point
    std::size_t non_finite = 0;
    std::size_t outside = 0;
  };
  /// The band's candidates from its points (stored in points_ and pixels_).
  void find_voxels(const Grid& grid, int width, Band& band);
  /// The same, back-projecting the band's rows one at a time instead (no points kept).
  void find_voxels_streamed(const Grid& grid, const DepthImage& depth, const PinholeCamera& camera, const Pose& pose,
                            Band& band);
  /// find_voxels' work on a run of the band's points in pixel order; `codes`
  /// receives their codes when not null.
  static void add_candidates(const Grid& grid, int width, std::span<const Vec3f> points, const std::uint32_t* pixels,
                             std::uint64_t* codes, Band& band, VoxelScan& scan);
  /// Adds the voxel codes codes[0, n) to the band's candidates.
  static void append_candidates(Band& band, const std::uint64_t* codes, std::size_t n);
  /// Sorts the band's candidates and merges repeated bricks; sets its counts from `scan`.
  static void finish_candidates(const Grid& grid, Band& band, const VoxelScan& scan);
  /// Empties the band's candidates for a scan of its pixels from the start.
  static VoxelScan start_scan(int width, Band& band);
  /// non_finite_ and out_of_bounds_ from the bands'.
  void sum_band_counts();

  // Kept between images: their buffers are reused (a fresh buffer costs a
  // page fault per 4 KiB on every frame).
  std::vector<Vec3f> points_;
  std::vector<std::uint32_t> pixels_;
  bool points_kept_ = false;  // points_ and pixels_ hold the last image's points
  std::vector<Rgb> colors_;
  std::vector<std::uint64_t> codes_;
  std::vector<Band> bands_;
  std::size_t non_finite_ = 0;
  std::size_t out_of_bounds_ = 0;
};

}  // namespace umbra
