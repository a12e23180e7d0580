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
  /// Appends the cells that became sites of `kind`.
  void append_added(int kind, BrickIndex brick, std::vector<CellCoord>& out) const;
};

/// The cells [lo, hi] per axis (inclusive) holding some of a brick's added
/// or removed sites of one kind; empty() when it has none.
struct CellRange {
  std::int64_t lo[3] = {0, 0, 0};
  std::int64_t hi[3] = {-1, -1, -1};
  [[nodiscard]] bool empty() const { return hi[0] < lo[0]; }
};
/// Per kind, the range of the cells that became sites and of those that
/// stopped being sites (a cheap bound on whom a change can reach).
struct ChangeExtent {
  std::array<CellRange, 2> added;
  std::array<CellRange, 2> removed;
};
ChangeExtent change_extent(const BrickChange& change, BrickIndex brick);

/// Per kind, the largest S of a cell's nearest site over a brick:
/// `farthest` counts a cell with none as kFarthest (any site within the cap
/// is nearer), `farthest_site` looks at the cells with a site only (0 if
/// none). A change at least `farthest` away lowers nothing in the brick, one
/// farther than `farthest_site` removes no cell's nearest site: an update
/// skips such bricks without looking at their cells.
struct SiteBounds {
  static constexpr std::uint32_t kFarthest = 0xFFFFFFFFu;
  std::array<std::uint32_t, 2> farthest{kFarthest, kFarthest};
  std::array<std::uint32_t, 2> farthest_site{0, 0};
};
SiteBounds site_bounds(const FieldLayout& layout, const BrickOffsets& offsets);

/// The least S from any cell of `brick` to any cell of `range`
/// (SiteBounds::kFarthest when beyond the window on some axis).
std::uint32_t least_squared(const FieldLayout& layout, BrickIndex brick, const CellRange& range);

/// The offsets of a brick that is not stored (see distance_field.hpp):
/// unknown at every cell, no occupied site within max_distance.
BrickOffsets trivial_offsets();

/// The sites one changed brick added in one kind.
struct AddedSites {
  BrickIndex brick;
  std::span<const CellCoord> sites;
  std::uint32_t least = 0;  ///< S from the lowered brick to the range of `sites` (the order they are tried in)
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
