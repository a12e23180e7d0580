// MapAgreement: how two maps of the same grid agree, voxel by voxel.
//
// For every finest voxel of the map's extent (or of a VoxelBox), the state
// (unknown, free, occupied) in a reference map and in another map: a 3 x 3
// table of voxel counts. A pruned node counts for each of the 8^d voxels it
// covers, and each map's state is by its own thresholds. From it: recall
// (the reference's occupied voxels occupied in the other map too), precision
// (the other's occupied voxels occupied in the reference too), the share of
// the reference's free voxels free in the other, and the share it leaves
// unknown.
//
// The one comparison of umbra: `umbra compare`, the fidelity benchmark
// (bench/fidelity_benchmark.cpp) and the integrator tests all call it, so
// their figures mean the same. Cost: one walk over both trees at once,
// descending only where either map has children (and, with a box, only into
// nodes that meet it): O(nodes of both maps) time, no allocation.
// Thread safety: both maps are held for reading during the walk (in a fixed
// order, so two comparisons of the same maps never wait for each other).
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "umbra/map/occupancy_map.hpp"
#include "umbra/map/voxel_box.hpp"

namespace umbra {

struct MapAgreement {
  /// voxels[reference state][other state], states indexed as OccupancyState.
  std::array<std::array<std::uint64_t, 3>, 3> voxels{};

  [[nodiscard]] std::uint64_t count(OccupancyState reference, OccupancyState other) const {
    return voxels[static_cast<int>(reference)][static_cast<int>(other)];
  }
  /// The reference's voxels in `state`.
  [[nodiscard]] std::uint64_t reference_count(OccupancyState state) const {
    const auto& row = voxels[static_cast<int>(state)];
    return row[0] + row[1] + row[2];
  }
  /// The other map's voxels in `state`.
  [[nodiscard]] std::uint64_t other_count(OccupancyState state) const {
    const int s = static_cast<int>(state);
    return voxels[0][s] + voxels[1][s] + voxels[2][s];
  }
  /// Share of the reference's occupied voxels that are occupied in the other
  /// map (1 when the reference has none).
  [[nodiscard]] double recall() const {
    return ratio(count(OccupancyState::occupied, OccupancyState::occupied), reference_count(OccupancyState::occupied));
  }
  /// Share of the other map's occupied voxels that are occupied in the
  /// reference (1 when the other has none).
  [[nodiscard]] double precision() const {
    return ratio(count(OccupancyState::occupied, OccupancyState::occupied), other_count(OccupancyState::occupied));
  }
  /// Share of the reference's free voxels that are free in the other map.
  [[nodiscard]] double free_agreement() const {
    return ratio(count(OccupancyState::free, OccupancyState::free), reference_count(OccupancyState::free));
  }
  /// Share of the reference's free voxels that the other map leaves unknown.
  [[nodiscard]] double free_left_unknown() const {
    return ratio(count(OccupancyState::free, OccupancyState::unknown), reference_count(OccupancyState::free));
  }

 private:
  static double ratio(std::uint64_t part, std::uint64_t whole) {
    return whole == 0 ? 1.0 : static_cast<double>(part) / static_cast<double>(whole);
  }
};

/// Compares `other` with `reference`, over the whole map or only the voxels
/// of `region`. Throws std::invalid_argument, naming both, when the maps'
/// resolutions or depth levels differ (their voxels are not the same).
[[nodiscard]] MapAgreement compare_maps(const OccupancyMap& reference, const OccupancyMap& other,
                                        const std::optional<VoxelBox>& region = std::nullopt);

}  // namespace umbra
