#include "field/site_changes.hpp"

#include <algorithm>
#include <bit>
#include <limits>

namespace umbra::detail {

void BrickChange::append_added(int kind, BrickIndex brick, std::vector<CellCoord>& out) const {
  const auto& b = kind == 0 ? before.occupied : before.unknown;
  const auto& a = kind == 0 ? after.occupied : after.unknown;
  for (int w = 0; w < 8; ++w) {
    for (std::uint64_t word = a[std::size_t(w)] & ~b[std::size_t(w)]; word != 0; word &= word - 1) {
      const int i = 64 * w + std::countr_zero(word);
      out.push_back({brick.x * kBrickCells + std::uint32_t(i & 7), brick.y * kBrickCells + std::uint32_t((i >> 3) & 7),
                     brick.z * kBrickCells + std::uint32_t(i >> 6)});
    }
  }
}

ChangeExtent change_extent(const BrickChange& change, BrickIndex brick) {
  ChangeExtent out;
  const std::int64_t first[3] = {std::int64_t(brick.x) * kBrickCells, std::int64_t(brick.y) * kBrickCells,
                                 std::int64_t(brick.z) * kBrickCells};
  const auto widen = [&](CellRange& r, std::uint64_t word, int w) {
    for (; word != 0; word &= word - 1) {
      const int i = 64 * w + std::countr_zero(word);
      const std::int64_t at[3] = {first[0] + (i & 7), first[1] + ((i >> 3) & 7), first[2] + (i >> 6)};
      const bool was_empty = r.empty();
      for (int a = 0; a < 3; ++a) {
        r.lo[a] = was_empty ? at[a] : std::min(r.lo[a], at[a]);
        r.hi[a] = was_empty ? at[a] : std::max(r.hi[a], at[a]);
      }
    }
  };
  for (int kind = 0; kind < 2; ++kind) {
    const auto& b = kind == 0 ? change.before.occupied : change.before.unknown;
    const auto& a = kind == 0 ? change.after.occupied : change.after.unknown;
    for (int w = 0; w < 8; ++w) {
      widen(out.added[std::size_t(kind)], a[std::size_t(w)] & ~b[std::size_t(w)], w);
      widen(out.removed[std::size_t(kind)], b[std::size_t(w)] & ~a[std::size_t(w)], w);
    }
  }
  return out;
}

SiteBounds site_bounds(const FieldLayout& layout, const BrickOffsets& offsets) {
  SiteBounds out;
  for (int kind = 0; kind < 2; ++kind) {
    std::uint32_t farthest = 0;
    std::uint32_t farthest_site = 0;
    for (const CellSites& cell : offsets) {
      const SiteOffset o = kind == 0 ? cell.occupied : cell.unknown;
      if (o.none()) {
        farthest = SiteBounds::kFarthest;
        continue;
      }
      const std::uint32_t s = layout.squared(o);
      farthest_site = std::max(farthest_site, s);
      farthest = std::max(farthest, s);
    }
    out.farthest[std::size_t(kind)] = farthest;
    out.farthest_site[std::size_t(kind)] = farthest_site;
  }
  return out;
}

BrickOffsets trivial_offsets() {
  BrickOffsets out;
  for (CellSites& c : out) c = {SiteOffset{}, SiteOffset{0, 0, 0}};
  return out;
}

namespace {

constexpr std::uint32_t kFar = std::numeric_limits<std::uint32_t>::max();

/// Per axis, the squared gap from each of the brick's 8 cells to the site
/// (kFar beyond the window), and the offsets.
struct AxisTerms {
  std::array<std::uint32_t, kBrickCells> squared{};
  std::array<std::int8_t, kBrickCells> offset{};
};

AxisTerms axis_terms(const FieldLayout& layout, std::uint32_t first_cell, std::uint32_t site) {
  AxisTerms t;
  const int w = layout.window();
  for (int i = 0; i < kBrickCells; ++i) {
    const std::int64_t n = std::int64_t(site) - std::int64_t(first_cell + std::uint32_t(i));
    t.squared[std::size_t(i)] = n < -w || n > w ? kFar : layout.squared_gap(int(n));
    t.offset[std::size_t(i)] = std::int8_t(n);
  }
  return t;
}

/// The fewest cells between [lo, lo + count) and [site_lo, site_hi] on one axis.
std::int64_t axis_gap(std::int64_t lo, std::int64_t count, std::int64_t site_lo, std::int64_t site_hi) {
  if (site_hi < lo) return lo - site_hi;
  if (site_lo > lo + count - 1) return site_lo - (lo + count - 1);
  return 0;
}

/// The least S from the brick's cells to anything in the cell box
/// [lo, hi] (kFar beyond the window).
std::uint32_t least_squared(const FieldLayout& layout, const std::int64_t first[3], const std::int64_t lo[3],
                            const std::int64_t hi[3]) {
  std::uint64_t sum = 0;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = axis_gap(first[a], kBrickCells, lo[a], hi[a]);
    if (n > layout.window()) return kFar;
    sum += layout.squared_gap(int(n));
  }
  return sum >= kFar ? kFar : std::uint32_t(sum);
}

/// S of each cell's nearest site in one kind, and the largest per row (8
/// cells along x), per slab (64 cells, one z) and over the brick: a site
/// lowers a cell only if its S is below all three.
class CurrentDistances {
 public:
  CurrentDistances(const FieldLayout& layout, const BrickOffsets& offsets, int kind) {
    for (int i = 0; i < kBrickVolume; ++i) {
      const SiteOffset o = kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown;
      s_[std::size_t(i)] = o.none() ? kFar : layout.squared(o);
    }
    for (int row = 0; row < kBrickCells * kBrickCells; ++row) update_row(row);
    for (int z = 0; z < kBrickCells; ++z) update_slab(z);
    update_brick();
  }
  [[nodiscard]] std::uint32_t cell(int i) const { return s_[std::size_t(i)]; }
  [[nodiscard]] std::uint32_t row(int r) const { return row_[std::size_t(r)]; }
  [[nodiscard]] std::uint32_t slab(int z) const { return slab_[std::size_t(z)]; }
  [[nodiscard]] std::uint32_t brick() const { return brick_; }
  void set(int i, std::uint32_t s) { s_[std::size_t(i)] = s; }
  void update_row(int r) {
    std::uint32_t m = 0;
    for (int x = 0; x < kBrickCells; ++x) m = std::max(m, s_[std::size_t(r * kBrickCells + x)]);
    row_[std::size_t(r)] = m;
  }
  void update_slab(int z) {
    std::uint32_t m = 0;
    for (int y = 0; y < kBrickCells; ++y) m = std::max(m, row_[std::size_t(z * kBrickCells + y)]);
    slab_[std::size_t(z)] = m;
  }
  void update_brick() { brick_ = *std::max_element(slab_.begin(), slab_.end()); }

 private:
  std::array<std::uint32_t, kBrickVolume> s_{};
  std::array<std::uint32_t, kBrickCells * kBrickCells> row_{};
  std::array<std::uint32_t, kBrickCells> slab_{};
  std::uint32_t brick_ = 0;
};

/// Lowers the cells of one kind by one site; returns whether any changed.
/// A site exactly as near to a cell as its nearest one replaces it when it
/// comes first in the canonical order (nearer_tie()), as in a rebuild.
bool lower_by_site(const FieldLayout& layout, const std::int64_t first[3], CellCoord site, int kind,
                   CurrentDistances& current, BrickOffsets& offsets) {
  const AxisTerms tx = axis_terms(layout, std::uint32_t(first[0]), site.x);
  const AxisTerms ty = axis_terms(layout, std::uint32_t(first[1]), site.y);
  const AxisTerms tz = axis_terms(layout, std::uint32_t(first[2]), site.z);
  const std::uint32_t least_x = *std::min_element(tx.squared.begin(), tx.squared.end());
  const std::uint32_t least_y = *std::min_element(ty.squared.begin(), ty.squared.end());
  bool changed = false;
  for (int z = 0; z < kBrickCells; ++z) {
    const std::uint64_t sz = tz.squared[std::size_t(z)];
    if (sz + least_y + least_x > current.slab(z)) continue;
    bool slab_changed = false;
    for (int y = 0; y < kBrickCells; ++y) {
      const int r = z * kBrickCells + y;
      const std::uint64_t yz = sz + ty.squared[std::size_t(y)];
      if (yz + least_x > current.row(r)) continue;
      bool row_changed = false;
      for (int x = 0; x < kBrickCells; ++x) {
        const std::uint64_t s = yz + tx.squared[std::size_t(x)];
        const int i = r * kBrickCells + x;
        if (s > current.cell(i) || !layout.within_cap(std::uint32_t(s))) continue;
        const SiteOffset o{tx.offset[std::size_t(x)], ty.offset[std::size_t(y)], tz.offset[std::size_t(z)]};
        SiteOffset& held = kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown;
        if (s == current.cell(i) && !nearer_tie(o, held)) continue;
        current.set(i, std::uint32_t(s));
        held = o;
        row_changed = true;
      }
      if (row_changed) {
        current.update_row(r);
        slab_changed = true;
      }
    }
    if (slab_changed) {
      current.update_slab(z);
      changed = true;
    }
  }
  if (changed) current.update_brick();
  return changed;
}

/// Whether sites at least `least` (S) from every cell of the brick can
/// lower or replace any cell's site: within the cap, and no farther than
/// the farthest current site (an equally near one may replace it).
bool may_lower(const FieldLayout& layout, std::uint32_t least, const CurrentDistances& current) {
  return least != kFar && layout.within_cap(least) && least <= current.brick();
}

}  // namespace

std::uint32_t least_squared(const FieldLayout& layout, BrickIndex brick, const CellRange& range) {
  const std::int64_t first[3] = {std::int64_t(brick.x) * kBrickCells, std::int64_t(brick.y) * kBrickCells,
                                 std::int64_t(brick.z) * kBrickCells};
  return least_squared(layout, first, range.lo, range.hi);
}

LoweringResult lower_by_added_sites(const FieldLayout& layout, BrickIndex brick, BrickOffsets& offsets,
                                   const std::array<std::vector<AddedSites>, 2>& added) {
  LoweringResult result;
  const std::int64_t first[3] = {std::int64_t(brick.x) * kBrickCells, std::int64_t(brick.y) * kBrickCells,
                                 std::int64_t(brick.z) * kBrickCells};
  for (int kind = 0; kind < 2; ++kind) {
    if (added[std::size_t(kind)].empty()) continue;
    CurrentDistances current(layout, offsets, kind);
    for (const AddedSites& group : added[std::size_t(kind)]) {
      // The whole changed brick first, then each of its sites.
      const std::int64_t lo[3] = {std::int64_t(group.brick.x) * kBrickCells, std::int64_t(group.brick.y) * kBrickCells,
                                  std::int64_t(group.brick.z) * kBrickCells};
      const std::int64_t hi[3] = {lo[0] + kBrickCells - 1, lo[1] + kBrickCells - 1, lo[2] + kBrickCells - 1};
      if (!may_lower(layout, least_squared(layout, first, lo, hi), current)) continue;
      for (const CellCoord& site : group.sites) {
        const std::int64_t at[3] = {site.x, site.y, site.z};
        if (!may_lower(layout, least_squared(layout, first, at, at), current)) continue;
        result.changed = lower_by_site(layout, first, site, kind, current, offsets) || result.changed;
      }
    }
  }
  return result;
}

}  // namespace umbra::detail
