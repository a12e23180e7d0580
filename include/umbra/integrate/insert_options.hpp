// Options and results of inserting one scan (OccupancyMap::insert_point_cloud).
//
// The rules the integrators follow (OctoMap's, voxel for voxel, for the
// simple and discrete ones; the UFOMap paper's coarse clearing for the fast
// one) are stated in docs/design.md and on OccupancyMap::insert_point_cloud.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "umbra/core/grid.hpp"
#include "umbra/core/threads.hpp"  // hardware_threads, max_threads: the bounds of InsertOptions::threads

namespace umbra {

enum class IntegratorKind { simple, discrete, fast, projective };

/// Angular sizes of a range image's pixels, in radians.
struct ScanResolution {
  double horizontal = 0.0;
  double vertical = 0.0;
};

/// "simple" / "discrete" / "fast" / "projective"; throws std::invalid_argument for anything else.
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
  /// projective: a voxel is cleared only when its centre lies at least this
  /// many voxel edges in front of the reading its centre projects onto
  /// (docs/design.md, "The projective integrator"). >= 0.
  double surface_margin = 0.0;
  /// projective, on a scan that is not a depth image: the angular size of
  /// the pixels of the images the scan is binned into (radians; about the
  /// scan's own spacing between neighbouring beams, horizontally and
  /// vertically); 0 on an axis: estimated per scan
  /// (InsertStats::scan_resolution says the values used).
  ScanResolution scan_resolution;
  /// Threads tracing rays; 0: all cores; at most max_threads(). When the
  /// system refuses to start some of them (a process limit), the scan runs
  /// on those that did start: InsertStats::threads says how many.
  unsigned threads = 0;
  /// When the scan was taken, in seconds on the map's clock (any epoch, e.g.
  /// ROS time). Given, the map's clock is advanced to it before the scan is
  /// inserted (OccupancyMap::advance_clock: the decay toward unknown since
  /// the last stamp, if set_decay asked for one). Nothing: the clock is left
  /// alone and the map changes exactly as without decay.
  std::optional<double> stamp;

  /// Throws std::invalid_argument naming the bad field (NaN max_range,
  /// clear_depth above the map's depth levels, negative fine_steps, a
  /// negative or non-finite surface_margin, a scan_resolution outside [0,
  /// 0.5), threads above max_threads(), a non-finite stamp).
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
  unsigned threads = 0;            ///< threads that traced the scan (the largest number, summed)
  /// Seconds the scan kept queries out: its apply phase (tracing, most of
  /// the insertion, lets them run). A query waits at most this long.
  double exclusive_seconds = 0.0;
  /// projective on a scan: the angular resolution of its images (radians;
  /// 0: none, e.g. a depth image, or too few points to bin).
  ScanResolution scan_resolution;

  InsertStats& operator+=(const InsertStats& other);
};

}  // namespace umbra
