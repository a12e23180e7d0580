// The exact distance transform of a chunk of 4^3 bricks (32^3 cells): for
// every cell, the offset to its nearest occupied site and to its nearest
// unknown site within the field's window, in the field's metric
// (field_layout.hpp).
//
// The metric is a sum over the axes of a function of each axis' offset, so
// the minimum over all sites splits into three one-dimensional passes
// (as in Felzenszwalb and Huttenlocher's separable transform): along x the
// nearest site of each row; along y the best (x result + y term) over the
// window; along z the same again. Each pass keeps the offsets of its best
// candidate, so the result is the site itself, not only its distance. A
// pass stops looking farther once the axis term alone exceeds the best
// found (the terms grow with the offset), which makes cells near
// obstacles cheap. The chunk reads the sites of its cells and of the
// window() cells around them.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "field/brick_sites.hpp"
#include "field/field_layout.hpp"
#include "umbra/core/function_ref.hpp"

namespace umbra::detail {

inline constexpr int kChunkBricks = 4;  // per axis
inline constexpr int kChunkCells = kChunkBricks * kBrickCells;

/// A cell's nearest sites, side by side so that a query reads one cache line.
struct CellSites {
  SiteOffset occupied;
  SiteOffset unknown;
};
/// The output of one brick, by cell_in_brick().
using BrickOffsets = std::array<CellSites, kBrickVolume>;

/// Sites of any brick: nullptr means the field holds nothing there
/// (absent_sites tells what it has then).
using SiteLookup = FunctionRef<const BrickBits*(BrickIndex)>;

class ChunkTransform {
 public:
  explicit ChunkTransform(const FieldLayout& layout);

  /// Computes the chunk whose first brick is `first` (a multiple of
  /// kChunkBricks per axis) and calls write(brick, offsets) for each of its
  /// bricks for which wanted(brick) holds.
  void run(BrickIndex first, SiteLookup sites, const BrickBits& absent_sites, FunctionRef<bool(BrickIndex)> wanted,
           FunctionRef<void(BrickIndex, const BrickOffsets&)> write);

 private:
  void load_sites(BrickIndex first, SiteLookup sites, const BrickBits& absent_sites);
  void transform(int kind);

  const FieldLayout& layout_;
  int window_;
  int span_;  // cells per axis of the input: kChunkCells + 2 window
  std::vector<std::uint8_t> sites_;    // span^3, bit 0 occupied, bit 1 unknown
  std::vector<std::int8_t> pass_x_;    // [z][y][x out]: x offset of the row's nearest site, or kNoSite
  std::vector<std::uint32_t> pass_y_;  // [z][y out][x out]: best S so far (UINT32_MAX: none)
  std::vector<std::array<std::int8_t, 2>> pass_y_offset_;
  std::array<std::vector<SiteOffset>, 2> result_;  // [kind][z out][y out][x out]
};

}  // namespace umbra::detail
