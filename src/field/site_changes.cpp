#include "field/site_changes.hpp"

#include <algorithm>
#include <bit>
#include <limits>

namespace umbra::detail {

bool BrickChange::adds(int kind) const {
  const auto& b = kind == 0 ? before.occupied : before.unknown;
  const auto& a = kind == 0 ? after.occupied : after.unknown;
  for (std::size_t w = 0; w < 8; ++w) {
    if ((a[w] & ~b[w]) != 0) return true;
  }
  return false;
}

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
  std::uint32_t least = kFar;  // over the 8 cells
};

AxisTerms axis_terms(const FieldLayout& layout, std::uint32_t first_cell, std::uint32_t site) {
  AxisTerms t;
  const int w = layout.window();
  for (int i = 0; i < kBrickCells; ++i) {
    const std::int64_t n = std::int64_t(site) - std::int64_t(first_cell + std::uint32_t(i));
    if (n < -w || n > w) {
      t.squared[std::size_t(i)] = kFar;
      continue;
    }
    t.squared[std::size_t(i)] = layout.squared_gap(int(n));
    t.offset[std::size_t(i)] = std::int8_t(n);
    t.least = std::min(t.least, t.squared[std::size_t(i)]);
  }
  return t;
}

}  // namespace

bool lower_by_added_sites(const FieldLayout& layout, BrickIndex brick, BrickOffsets& offsets,
                          const std::array<std::span<const CellCoord>, 2>& added) {
  bool changed = false;
  const std::uint32_t first[3] = {brick.x * kBrickCells, brick.y * kBrickCells, brick.z * kBrickCells};
  std::array<std::uint32_t, kBrickVolume> current{};  // S of each cell's nearest site (kFar: none)
  for (int kind = 0; kind < 2; ++kind) {
    if (added[std::size_t(kind)].empty()) continue;
    std::uint32_t worst = 0;
    for (int i = 0; i < kBrickVolume; ++i) {
      const SiteOffset o = kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown;
      current[std::size_t(i)] = o.none() ? kFar : layout.squared(o);
      worst = std::max(worst, current[std::size_t(i)]);
    }
    for (const CellCoord& site : added[std::size_t(kind)]) {
      const AxisTerms tx = axis_terms(layout, first[0], site.x);
      if (tx.least == kFar) continue;
      const AxisTerms ty = axis_terms(layout, first[1], site.y);
      if (ty.least == kFar) continue;
      const AxisTerms tz = axis_terms(layout, first[2], site.z);
      if (tz.least == kFar) continue;
      // No cell of the brick can get nearer than its worst current one.
      const std::uint64_t least = std::uint64_t(tx.least) + ty.least + tz.least;
      if (least >= worst || !layout.within_cap(std::uint32_t(std::min<std::uint64_t>(least, kFar)))) continue;
      bool lowered = false;
      for (int z = 0; z < kBrickCells; ++z) {
        if (tz.squared[std::size_t(z)] == kFar) continue;
        for (int y = 0; y < kBrickCells; ++y) {
          if (ty.squared[std::size_t(y)] == kFar) continue;
          const std::uint32_t yz = ty.squared[std::size_t(y)] + tz.squared[std::size_t(z)];
          for (int x = 0; x < kBrickCells; ++x) {
            if (tx.squared[std::size_t(x)] == kFar) continue;
            const std::uint32_t s = yz + tx.squared[std::size_t(x)];
            const int i = x + kBrickCells * y + kBrickCells * kBrickCells * z;
            if (s >= current[std::size_t(i)] || !layout.within_cap(s)) continue;  // a tie keeps the old site
            current[std::size_t(i)] = s;
            const SiteOffset o{tx.offset[std::size_t(x)], ty.offset[std::size_t(y)], tz.offset[std::size_t(z)]};
            (kind == 0 ? offsets[std::size_t(i)].occupied : offsets[std::size_t(i)].unknown) = o;
            lowered = true;
          }
        }
      }
      if (!lowered) continue;
      changed = true;
      worst = 0;
      for (int i = 0; i < kBrickVolume; ++i) worst = std::max(worst, current[std::size_t(i)]);
    }
  }
  return changed;
}

}  // namespace umbra::detail
