// Color samples: the colors a scan's points add to the map (after its
// occupancy update, OccupancyTree::add_colors).
//
// The points that give a hit, stably sorted by voxel, so that each voxel
// blends its samples in scan order. Whether a point gives a hit is decided
// by the end point its ray goes to: the point itself (simple), the centre of
// its voxel (discrete) or the first point that fell in its voxel (fast).
//
// With a thread pool every step runs a part per worker and gives the same
// samples, in the same order, as one thread: the voxels of contiguous parts
// of the scan; their stable sort (parallel_radix_sort); the hit decisions
// over parts of the sorted samples that begin at a voxel's first sample.
// Serially these steps were 2% of the one-thread time of the TUM frames at
// 4 mm with color (fast integrator), which two threads could not share.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "core/thread_pool.hpp"
#include "integrate/ray_tracer.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra {

/// The color samples of a scan from `origin` (one color per point), of the
/// points inside `box` (when given); `pool`: null for one thread. `codes`:
/// the points' voxel codes (voxel_codes) when the caller has them, or empty.
std::vector<OccupancyTree::ColorSample> color_samples(const Grid& grid, Vec3f origin, std::span<const Vec3f> points,
                                                      std::span<const Rgb> colors, const InsertOptions& options,
                                                      const std::optional<KeyBox>& box, ThreadPool* pool,
                                                      std::span<const std::uint64_t> codes = {});

}  // namespace umbra
