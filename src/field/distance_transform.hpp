// The exact distance transform of a chunk of bricks: for every cell, the
// offset to its nearest occupied site and to its nearest unknown site
// within the field's window, in the field's metric (field_layout.hpp).
//
// The metric is a sum over the axes of a function of each axis' offset, so
// the minimum over all sites splits into three one-dimensional passes, as
// in Felzenszwalb and Huttenlocher's separable transform: along x the
// nearest site of each row; along y the best (x result + y term); along z
// the same again. Each pass keeps the offsets of its best candidate, so the
// result is the site itself, not only its distance.
//
// The y and z passes are lower envelopes of parabolas, linear in the
// column's length. The axis term of an offset n != 0 is (2 (|n| - 1) E + 1)^2:
// for a site before the cell that is the parabola (X - C)^2 with X = 2 E y
// and C = 2 E s + 2 E - 1, for a site after it the mirror image. So the
// minimum is that of the site at the cell itself, the envelope of the
// sites before the cell and that of the sites after it; each envelope is
// built while walking the column from its end, a site joining before the
// first cell after it is answered. In integers, and with each side's
// envelope holding its own side only, the pick among equally near sites
// is the canonical one of nearer_tie() (field_layout.hpp).
//
// A chunk is chunk_bricks(window) bricks per axis: large enough that the
// window read around it (the sites of `window` cells on each side) costs
// a few times its own cells, not dozens.
//
// The window may be narrower than the field's (FieldLayout::window()):
// then the transform is exact for the cells whose nearest site is nearer
// than any site outside that window can be (S < squared_gap(window + 1))
// and answers "none" for the others (reach_cap()), which an update then
// sends through the full window (docs/design.md, "Updates").
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "field/brick_sites.hpp"
#include "field/field_layout.hpp"
#include "umbra/core/function_ref.hpp"

namespace umbra::detail {

/// Bricks per axis of a chunk for a field's window.
inline int chunk_bricks(int window) {
  const int wanted = (2 * window + kBrickCells - 1) / kBrickCells;  // cells per axis >= twice the window
  return wanted < 4 ? 4 : (wanted > 16 ? 16 : wanted);
}

/// A cell's nearest sites, side by side so that a query reads one cache line.
struct CellSites {
  SiteOffset occupied;
  SiteOffset unknown;
};
/// The output of one brick, by cell_in_brick().
using BrickOffsets = std::array<CellSites, kBrickVolume>;

/// Sites of any brick (never nullptr).
using SiteLookup = FunctionRef<const BrickBits*(BrickIndex)>;

/// The largest S a transform with `window` cells on each side answers
/// exactly: the field's cap at its full window; below it, one less than
/// the least S of a site outside the window (squared_gap(window + 1)), so
/// that no site it did not read can be as near as one it answers.
std::uint64_t reach_cap(const FieldLayout& layout, int window);

/// Where the wanted bricks of a chunk read: a wanted brick's cells depend
/// on the sites within `window` cells of it only, so the passes skip the
/// rows, columns and places no wanted brick reads (the raised bricks of an
/// update are a few in a chunk: about 100 of 2,197 on the TUM benchmark).
/// Places are span coordinates (distance_transform.cpp).
class ChunkReach {
 public:
  /// `wanted` by (z * bricks + y) * bricks + x.
  void compute(const std::vector<bool>& wanted, int bricks, int window);
  /// Some wanted brick reads the row (y, z) (pass x).
  [[nodiscard]] bool row(std::size_t y, std::size_t z) const { return rows_[z * std::size_t(span_) + y] != 0; }
  /// Some wanted brick of slab (x brick) `slab` reads the row (y, z) (pass y's inputs).
  [[nodiscard]] bool slab_row(std::size_t slab, std::size_t y, std::size_t z) const {
    return slab_rows_[(slab * std::size_t(span_) + z) * std::size_t(span_) + y] != 0;
  }
  /// Some wanted brick of the slab reads the plane z (pass y's columns).
  [[nodiscard]] bool slab_z(std::size_t slab, std::size_t z) const { return slab_z_[slab * std::size_t(span_) + z] != 0; }
  /// Some wanted brick reads a row (y, z) with y in [y0, y1], z in [z0, z1] (loading the sites).
  [[nodiscard]] bool any_row(std::size_t y0, std::size_t y1, std::size_t z0, std::size_t z1) const {
    for (std::size_t z = z0; z <= z1; ++z) {
      for (std::size_t y = y0; y <= y1; ++y) {
        if (row(y, z)) return true;
      }
    }
    return false;
  }
  /// Some wanted brick of the column (x, y bricks) reads z (pass z's inputs).
  [[nodiscard]] bool column_z(std::size_t bx, std::size_t by, std::size_t z) const {
    return column_z_[(bx * std::size_t(bricks_) + by) * std::size_t(span_) + z] != 0;
  }

 private:
  int bricks_ = 0;
  int span_ = 0;
  std::vector<int> first_, last_;  // per place: the bricks (along an axis) that read it
  std::vector<int> slab_count_, column_count_;  // prefix counts of wanted bricks
  std::vector<std::uint8_t> rows_, slab_rows_, slab_z_, column_z_;
};

class ChunkTransform {
 public:
  /// `window` <= layout.window() (see the file comment).
  ChunkTransform(const FieldLayout& layout, int window);

  [[nodiscard]] int bricks_per_axis() const { return bricks_; }
  /// Computes the chunk whose first brick is `first` (a multiple of
  /// bricks_per_axis() per axis) and calls write(brick, offsets) for each of
  /// its bricks for which wanted(brick) holds. Only the kinds in `kinds`
  /// (bit 0 occupied, bit 1 unknown) are computed; the others' offsets in
  /// `offsets` are meaningless.
  void run(BrickIndex first, SiteLookup sites, FunctionRef<bool(BrickIndex)> wanted,
           FunctionRef<void(BrickIndex, const BrickOffsets&)> write, int kinds = 3);

 private:
  /// One column's minimum of (value at s + axis term of s - t) for the
  /// output cells t in [window, window + out): values[s] (kNone: no site),
  /// stride apart; best[t - window] and from[t - window] (the site's s).
  void column(const std::uint32_t* values, std::size_t stride, std::uint32_t* best, std::int16_t* from);
  void load_sites(BrickIndex first, SiteLookup sites);
  void transform(int kind);

  const FieldLayout& layout_;
  int window_;  // cells read on each side of the chunk
  int bricks_;  // per axis
  int out_;     // output cells per axis
  int span_;    // input cells per axis: out + 2 window
  std::uint32_t e2_;  // 2 E
  std::uint64_t cap_;  // the largest S answered: reach_cap(layout, window)
  std::vector<std::uint8_t> sites_;    // span^3, bit 0 occupied, bit 1 unknown
  std::vector<std::int8_t> pass_x_;    // [z][y][x out]: x offset of the row's nearest site, or kNoSite
  std::vector<std::uint32_t> column_;  // one column's values
  std::vector<std::uint32_t> pass_y_;  // [z][y out][x out]: best S (kNone: none)
  std::vector<std::array<std::int8_t, 2>> pass_y_offset_;
  std::array<std::vector<SiteOffset>, 2> result_;  // [kind][z out][y out][x out]
  // The envelope's scratch: parabola sites and boundaries, per side.
  std::vector<int> hull_;
  std::vector<std::int64_t> hull_c_;  // each hull parabola's C and F (see column())
  std::vector<std::int64_t> hull_f_;
  std::vector<std::uint32_t> best_;
  std::vector<std::int16_t> from_;
  // The wanted bricks of the current run by (x, y) (pass z skips the
  // columns where no brick is wanted), and where they read.
  std::vector<bool> wanted_xy_;
  ChunkReach reach_;
};

}  // namespace umbra::detail
