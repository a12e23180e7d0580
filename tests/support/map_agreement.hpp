// MapAgreement: how two maps of the same grid agree, voxel by voxel.
//
// For every finest voxel of the map's extent, the state (unknown, free,
// occupied) in a reference map and in another map: a 3 x 3 table of voxel
// counts. A pruned node counts for each of the 8^d voxels it covers. From it:
// recall (reference's occupied voxels occupied in the other map too),
// precision (other's occupied voxels occupied in the reference too) and the
// share of the reference's free voxels the other leaves unknown.
//
// Header-only over the public API, so that the tests (fast integrator
// agreement) and the benchmarks (bench/fidelity_benchmark.cpp) compute the
// very same figures. Cost: one pass over the leaves of each map (both are
// listed in Morton order and walked as two tilings of the same code range),
// O(leaves) time and memory.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

struct MapAgreement {
  /// voxels[reference state][other state], states indexed as OccupancyState.
  std::array<std::array<std::uint64_t, 3>, 3> voxels{};

  [[nodiscard]] std::uint64_t count(OccupancyState reference, OccupancyState other) const {
    return voxels[static_cast<int>(reference)][static_cast<int>(other)];
  }
  [[nodiscard]] std::uint64_t reference_count(OccupancyState state) const {
    const auto& row = voxels[static_cast<int>(state)];
    return row[0] + row[1] + row[2];
  }
  [[nodiscard]] std::uint64_t other_count(OccupancyState state) const {
    const int s = static_cast<int>(state);
    return voxels[0][s] + voxels[1][s] + voxels[2][s];
  }
  /// Share of the reference's occupied voxels that are occupied in the other map.
  [[nodiscard]] double recall() const {
    return ratio(count(OccupancyState::occupied, OccupancyState::occupied), reference_count(OccupancyState::occupied));
  }
  /// Share of the other map's occupied voxels that are occupied in the reference.
  [[nodiscard]] double precision() const {
    return ratio(count(OccupancyState::occupied, OccupancyState::occupied), other_count(OccupancyState::occupied));
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

namespace agreement_detail {

/// A childless node: the Morton codes [first, first + 8^depth) and their state.
struct LeafSpan {
  std::uint64_t first;
  std::uint64_t count;
  OccupancyState state;
};

inline std::vector<LeafSpan> leaf_spans(const OccupancyMap& map) {
  std::vector<LeafSpan> spans;
  map.for_each_leaf([&](const Node& node) {
    spans.push_back({node.code(), std::uint64_t{1} << (3 * node.depth), node.state});
  });
  return spans;
}

/// Voxels of the node [first, first + count) (count a power of 8) inside the
/// keys [lo, hi] on every axis.
inline std::uint64_t voxels_inside(std::uint64_t first, std::uint64_t count, Key lo, Key hi) {
  const Key corner = morton::decode(first);
  const std::uint32_t side = std::uint32_t{1} << (std::countr_zero(count) / 3);
  std::uint64_t inside = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t begin = std::max<std::int64_t>(corner[axis], lo[axis]);
    const std::int64_t end = std::min<std::int64_t>(std::int64_t{corner[axis]} + side, std::int64_t{hi[axis]} + 1);
    if (end <= begin) return 0;
    inside *= static_cast<std::uint64_t>(end - begin);
  }
  return inside;
}

}  // namespace agreement_detail

/// Compares `other` with `reference`; both must have the same resolution and
/// depth levels (std::invalid_argument otherwise). With `keys` = {lo, hi},
/// only the voxels with lo <= key <= hi on every axis count (a bounding box's
/// inside, away from its faces, where the integrators' box rules differ).
inline MapAgreement compare_maps(const OccupancyMap& reference, const OccupancyMap& other,
                                 const std::optional<std::pair<Key, Key>>& keys = std::nullopt) {
  if (reference.resolution() != other.resolution() || reference.depth_levels() != other.depth_levels()) {
    throw std::invalid_argument("compare_maps: the maps have different grids");
  }
  // The leaves of a map tile its whole code range in Morton order, so the
  // two lists are walked like a merge of two sorted interval lists.
  const std::vector<agreement_detail::LeafSpan> a = agreement_detail::leaf_spans(reference);
  const std::vector<agreement_detail::LeafSpan> b = agreement_detail::leaf_spans(other);
  MapAgreement agreement;
  std::size_t i = 0;
  std::size_t j = 0;
  std::uint64_t position = 0;
  while (i < a.size() && j < b.size()) {
    const std::uint64_t end_a = a[i].first + a[i].count;
    const std::uint64_t end_b = b[j].first + b[j].count;
    const std::uint64_t end = end_a < end_b ? end_a : end_b;
    // Both lists tile the codes with whole nodes, so [position, end) is one
    // node too: the smaller of the two.
    agreement.voxels[static_cast<int>(a[i].state)][static_cast<int>(b[j].state)] +=
        keys ? agreement_detail::voxels_inside(position, end - position, keys->first, keys->second) : end - position;
    position = end;
    i += end_a == end;
    j += end_b == end;
  }
  return agreement;
}

}  // namespace umbra::test
