// DecayRates: how fast a map forgets what it has not seen for a while
// (OccupancyMap::set_decay; the rule in docs/design.md, "Decay toward unknown").
//
// Every voxel's log-odds moves toward 0, the value of a never-observed voxel
// (unknown), linearly with the time on the map's clock: positive (occupied)
// values by `occupied_per_second`, negative (free) ones by
// `free_per_second`, stopping at 0. A voxel that reaches 0 is unknown again,
// exactly as if never observed. A scan that sees the voxel again adds its
// hit or miss as usual, so a voxel seen often stays certain and a person who
// walked through fades out.
#pragma once

#include <optional>

#include "umbra/core/aabb.hpp"

namespace umbra {

struct DecayRates {
  /// Log-odds per second taken off occupied (positive) values; 0: they stay.
  double occupied_per_second = 0.0;
  /// Log-odds per second added to free (negative) values; 0: they stay.
  double free_per_second = 0.0;
  /// Only the voxels this box meets decay (metres; the same voxels as
  /// set_bounding_box's, umbra/map/voxel_box.hpp); nothing: every voxel.
  std::optional<Aabb> region;

  /// False when both rates are 0: the clock then changes nothing.
  [[nodiscard]] bool enabled() const { return occupied_per_second > 0.0 || free_per_second > 0.0; }
  /// Throws std::invalid_argument naming the bad field: a rate that is
  /// negative or not finite, a region with min > max or a non-finite corner.
  void validate() const;
  friend bool operator==(const DecayRates&, const DecayRates&) = default;
};

}  // namespace umbra
