// End voxels: the voxels a scan's points fall in, one ray each for the
// discrete and fast integrators (see Integrator::trace).
//
// The points are split into contiguous parts, one per worker. Each part's
// voxels are found, sorted by Morton code and made unique on its worker
// (end_voxels); the parts are then merged into one sorted list without
// repeats (merge_end_voxels). For every voxel the list holds the first point
// of the scan that fell in it, as a stable sort of all points followed by
// std::unique would: within a part the sort is stable, and on equal codes
// the merge keeps the earlier part's entry.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

struct InsertStats;

/// One voxel that end points fall in: its Morton code and the first point
/// (in scan order) that fell in it.
struct EndVoxel {
  std::uint64_t code;
  std::uint32_t point;
};

/// The end voxels of points [first, first + count) of a scan, sorted by
/// code, each with the first of those points that fell in it, and what was
/// skipped (non-finite points, points outside the map).
void end_voxels(const Grid& grid, std::span<const Vec3f> points, std::size_t first, std::size_t count,
                std::vector<EndVoxel>& voxels, InsertStats& stats);

/// The end voxels of consecutive parts of a scan (each as end_voxels gives
/// them, in scan order of the parts) as one sorted list without repeats.
/// Empties the parts.
std::vector<EndVoxel> merge_end_voxels(std::vector<std::vector<EndVoxel>>& parts);

}  // namespace umbra
