// The incremental steps of DistanceField::update() (docs/design.md,
// "Distance field"): how the sites changed, and which cells that changes.
//
// Per kind (occupied, unknown), the sites after an update are the sites
// before it, less the removed ones, plus the added ones. So for a cell
//   - whose nearest site was not removed, that site is still a nearest one
//     among the old sites that remain, and the new nearest is the nearer of
//     it and the nearest added site (an exact minimum; of equally near
//     sites the one first in nearer_tie(), as the transform keeps):
//     lower_by_added_sites();
//   - whose nearest site was removed, nothing local tells the new one: its
//     brick goes through the full transform (distance_transform.hpp).
// A brick none of whose cells falls in the second case never needs the
// transform, which is what makes an update cost about the cells a scan
// changes rather than everything within max_distance of them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "field/brick_sites.hpp"
#include "field/distance_transform.hpp"
#include "field/field_layout.hpp"

namespace umbra::detail {

/// A cell by its coordinates in cells (key >> depth).
struct CellCoord {
  std::uint32_t x = 0, y = 0, z = 0;
};

/// The sites of a brick before and after an update.
struct BrickChange {
  BrickBits before;
  BrickBits after;
  /// Kind 0 occupied, 1 unknown: the cell was a site of that kind and is not any more.
  [[nodiscard]] bool removed(int kind, int cell) const {
    const auto& b = kind == 0 ? before.occupied : before.unknown;
    const auto& a = kind == 0 ? after.occupied : after.unknown;
    return ((b[std::size_t(cell >> 6)] & ~a[std::size_t(cell >> 6)]) >> (cell & 63) & 1u) != 0;
  }
  [[nodiscard]] bool adds(int kind) const;
  /// Appends the cells that became sites of `kind`.
  void append_added(int kind, BrickIndex brick, std::vector<CellCoord>& out) const;
};

/// The offsets of a brick that is not stored (see distance_field.hpp):
/// unknown at every cell, no occupied site within max_distance.
BrickOffsets trivial_offsets();

/// The sites one changed brick added in one kind.
struct AddedSites {
  BrickIndex brick;
  std::span<const CellCoord> sites;
};

struct LoweringResult {
  bool changed = false;  ///< some cell got a nearer site (or an equally near one first in nearer_tie())
};

/// Lowers `offsets` (brick `brick`) by the added sites of each kind
/// (added[0] occupied, added[1] unknown; those out of reach are skipped).
/// The bound on what a site can lower goes from the brick to its slabs and
/// rows of cells, so a site that lowers nothing costs a few comparisons,
/// not one per cell.
LoweringResult lower_by_added_sites(const FieldLayout& layout, BrickIndex brick, BrickOffsets& offsets,
                                    const std::array<std::vector<AddedSites>, 2>& added);

}  // namespace umbra::detail
