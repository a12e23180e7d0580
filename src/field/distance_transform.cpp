#include "field/distance_transform.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace umbra::detail {
namespace {
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
}

std::uint64_t reach_cap(const FieldLayout& layout, int window) {
  if (window >= layout.window()) return layout.cap_squared();
  return std::min<std::uint64_t>(layout.cap_squared(), std::uint64_t(layout.squared_gap(window + 1)) - 1);
}

ChunkTransform::ChunkTransform(const FieldLayout& layout, int window)
    : layout_(layout),
      window_(window),
      bricks_(chunk_bricks(window)),
      out_(chunk_bricks(window) * kBrickCells),
      span_(out_ + 2 * window),
      e2_(2u << layout.depth()),
      cap_(reach_cap(layout, window)) {
  const std::size_t span = std::size_t(span_);
  const std::size_t out = std::size_t(out_);
  sites_.resize(span * span * span);
  pass_x_.resize(span * span * out);
  column_.resize(span);
  pass_y_.resize(span * out * out);
  pass_y_offset_.resize(pass_y_.size());
  for (auto& r : result_) r.resize(out * out * out);
  hull_.resize(span);
  hull_c_.resize(span);
  hull_f_.resize(span);
  best_.resize(out);
  from_.resize(out);
}

void ChunkTransform::load_sites(BrickIndex first, SiteLookup sites) {
  // Input cells [first * 8 - window, first * 8 + out + window) per axis;
  // cells outside the map hold no site.
  const std::int64_t origin[3] = {std::int64_t(first.x) * kBrickCells - window_,
                                  std::int64_t(first.y) * kBrickCells - window_,
                                  std::int64_t(first.z) * kBrickCells - window_};
  const std::int64_t limit = layout_.cells_per_axis();
  std::fill(sites_.begin(), sites_.end(), std::uint8_t{0});
  std::int64_t brick_lo[3];
  std::int64_t brick_hi[3];
  for (int a = 0; a < 3; ++a) {
    const std::int64_t lo = std::max<std::int64_t>(origin[a], 0);
    const std::int64_t hi = std::min<std::int64_t>(origin[a] + span_, limit) - 1;
    brick_lo[a] = lo / kBrickCells;
    brick_hi[a] = hi / kBrickCells;
  }
  const std::size_t span = std::size_t(span_);
  for (std::int64_t bz = brick_lo[2]; bz <= brick_hi[2]; ++bz) {
    for (std::int64_t by = brick_lo[1]; by <= brick_hi[1]; ++by) {
      for (std::int64_t bx = brick_lo[0]; bx <= brick_hi[0]; ++bx) {
        const std::int64_t base[3] = {bx * kBrickCells - origin[0], by * kBrickCells - origin[1],
                                      bz * kBrickCells - origin[2]};
        // Rows no wanted brick reads stay empty (pass x skips them too).
        if (!reach_.any_row(std::size_t(std::max<std::int64_t>(base[1], 0)),
                            std::size_t(std::min<std::int64_t>(base[1] + kBrickCells, span_) - 1),
                            std::size_t(std::max<std::int64_t>(base[2], 0)),
                            std::size_t(std::min<std::int64_t>(base[2] + kBrickCells, span_) - 1))) {
          continue;
        }
        const BrickBits& bits = *sites(BrickIndex{std::uint32_t(bx), std::uint32_t(by), std::uint32_t(bz)});
        for (int kind = 0; kind < 2; ++kind) {
          const std::array<std::uint64_t, 8>& words = kind == 0 ? bits.occupied : bits.unknown;
          for (int w = 0; w < 8; ++w) {
            for (std::uint64_t word = words[std::size_t(w)]; word != 0; word &= word - 1) {
              const int i = 64 * w + std::countr_zero(word);
              const std::int64_t x = base[0] + (i & 7), y = base[1] + ((i >> 3) & 7), z = base[2] + (i >> 6);
              if (x < 0 || y < 0 || z < 0 || x >= span_ || y >= span_ || z >= span_) continue;
              sites_[(std::size_t(z) * span + std::size_t(y)) * span + std::size_t(x)] |= std::uint8_t(1u << kind);
            }
          }
        }
      }
    }
  }
}

void ChunkTransform::column(const std::uint32_t* values, std::size_t stride, std::uint32_t* best,
                            std::int16_t* from) {
  // Integers throughout (no rounding), and each side's envelope holds only
  // the sites on its side of the cell: the pick among equally near sites is
  // then the canonical one (field_layout.hpp, nearer_tie()), a function of
  // the sites alone, so that an update's lowering can apply the same rule
  // and any region of cells can be transformed and agree with a rebuild.
  __extension__ typedef __int128 Wide;  // products of a parabola's value and a position (deep cells, wide windows)
  const int w = window_;
  const std::uint64_t cap = cap_;
  const std::int64_t e2 = std::int64_t(e2_);
  // The site at the cell itself (offset 0 comes first among equals).
  for (int t = 0; t < out_; ++t) {
    const std::uint32_t v = values[std::size_t(w + t) * stride];
    best[t] = v;
    from[t] = std::int16_t(v == kNone ? -1 : w + t);
  }
  // One side: the sites at positions before the cell, in the order `dir`
  // walks (+1: smaller positions, the cell's offset negative; -1: larger).
  // In walking order a site at step u has C_u = e2 u + e2 - 1, so its term
  // for the cell at step T > u is (e2 T - C_u)^2, a parabola in X = e2 T;
  // F_u = v_u + C_u^2, and u supersedes q (before it) from
  // X = (F_u - F_q) / (2 (C_u - C_q)) on. The cells are visited in walking
  // order too, each after the sites before it joined the envelope.
  for (const int dir : {1, -1}) {
    const auto position = [&](int u) { return dir > 0 ? u : span_ - 1 - u; };
    int k = -1;
    int j = 0;
    int next = 0;  // the next step to join the envelope
    const int first_cell = dir > 0 ? w : span_ - w - out_;
    for (int c = 0; c < out_; ++c) {
      const int cell = first_cell + c;  // step of this cell
      for (; next < cell; ++next) {
        const std::uint32_t v = values[std::size_t(position(next)) * stride];
        if (v == kNone) continue;
        const std::int64_t cu = e2 * next + e2 - 1;
        const std::int64_t fu = std::int64_t(v) + cu * cu;
        while (k >= 1) {
          // Drop the top q when u supersedes it no later than q superseded p.
          const std::int64_t cq = hull_c_[std::size_t(k)], fq = hull_f_[std::size_t(k)];
          const std::int64_t cp = hull_c_[std::size_t(k - 1)], fp = hull_f_[std::size_t(k - 1)];
          if (Wide(fu - fq) * Wide(cq - cp) > Wide(fq - fp) * Wide(cu - cq)) break;
          --k;
        }
        ++k;
        hull_[std::size_t(k)] = next;
        hull_c_[std::size_t(k)] = cu;
        hull_f_[std::size_t(k)] = fu;
      }
      if (k < 0) continue;
      j = std::min(j, k);
      const std::int64_t x = e2 * cell;
      // The last of the equally low (the nearest to the cell) is kept.
      while (j < k && Wide(hull_f_[std::size_t(j + 1)] - hull_f_[std::size_t(j)]) <=
                          Wide(2 * x) * Wide(hull_c_[std::size_t(j + 1)] - hull_c_[std::size_t(j)])) {
        ++j;
      }
      const int u = hull_[std::size_t(j)];
      const std::uint64_t gap = std::uint64_t(cell - u - 1) * std::uint64_t(e2) + 1;
      const std::uint64_t total = std::uint64_t(values[std::size_t(position(u)) * stride]) + gap * gap;
      const int t = dir > 0 ? c : out_ - 1 - c;
      // Equally near (the canonical order, nearer_tie()): the smaller
      // |offset|, and of -n and +n the negative. A site of this side beats
      // the one kept so far only when strictly nearer in steps: on the
      // first side that one is the cell's own, on the second one of the
      // first side (negative offsets).
      const int held = from[t] < 0 ? -1 : std::abs(from[t] - (w + t));  // |offset| kept so far
      const bool tie_wins = total == std::uint64_t(best[t]) && dir < 0 && held > 0 && cell - u < held;
      if (total < std::uint64_t(best[t]) || tie_wins) {
        best[t] = total > cap ? kNone - 1 : std::uint32_t(total);
        from[t] = std::int16_t(position(u));
      }
    }
  }
  // Beyond the cap nothing counts (and the offsets then fit the window).
  for (int t = 0; t < out_; ++t) {
    if (best[t] != kNone && std::uint64_t(best[t]) > cap) {
      best[t] = kNone;
      from[t] = -1;
    }
  }
}

void ChunkTransform::transform(int kind) {
  const std::uint8_t mask = std::uint8_t(1u << kind);
  const int w = window_;
  const std::size_t span = std::size_t(span_);
  const std::size_t out = std::size_t(out_);
  // Pass x: nearest site along each row, for the output columns, in the
  // rows some wanted brick reads (Reach).
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t y = 0; y < span; ++y) {
      if (!reach_.row(y, z)) continue;
      const std::uint8_t* row = &sites_[(z * span + y) * span];
      std::int8_t* dest = &pass_x_[(z * span + y) * out];
      int last = -1000000;
      for (int x = 0; x < w + int(out); ++x) {
        if (row[x] & mask) last = x;
        if (x >= w) dest[x - w] = std::int8_t(x - last <= w ? last - x : SiteOffset::kNoSite);
      }
      int next = 1000000;
      for (int x = int(span) - 1; x >= w; --x) {
        if (row[x] & mask) next = x;
        if (x < w + int(out) && next - x <= w) {
          std::int8_t& d = dest[x - w];
          if (d == SiteOffset::kNoSite || next - x < -d) d = std::int8_t(next - x);
        }
      }
    }
  }
  // Pass y: along each column of the output's x, at the z some wanted
  // brick of the slab reads; the rows none of them reads count as empty.
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t x = 0; x < out; ++x) {
      const std::size_t slab = x / kBrickCells;
      if (!reach_.slab_z(slab, z)) continue;  // no wanted brick of this slab reads this z
      for (std::size_t y = 0; y < span; ++y) {
        const std::int8_t dx = pass_x_[(z * span + y) * out + x];
        column_[y] = dx == SiteOffset::kNoSite || !reach_.slab_row(slab, y, z) ? kNone : layout_.squared_gap(dx);
      }
      column(column_.data(), 1, best_.data(), from_.data());
      for (std::size_t t = 0; t < out; ++t) {
        const std::size_t at = (z * out + t) * out + x;
        pass_y_[at] = best_[t];
        if (best_[t] != kNone) {
          const int s = from_[t];
          pass_y_offset_[at] = {pass_x_[(z * span + std::size_t(s)) * out + x], std::int8_t(s - (w + int(t)))};
        }
      }
    }
  }
  // Pass z: along each column of the output's x and y.
  std::vector<SiteOffset>& result = result_[std::size_t(kind)];
  for (std::size_t y = 0; y < out; ++y) {
    for (std::size_t x = 0; x < out; ++x) {
      const std::size_t bx = x / kBrickCells, by = y / kBrickCells;
      if (!wanted_xy_[bx + std::size_t(bricks_) * by]) continue;
      for (std::size_t z = 0; z < span; ++z) {
        column_[z] = reach_.column_z(bx, by, z) ? pass_y_[(z * out + y) * out + x] : kNone;
      }
      column(column_.data(), 1, best_.data(), from_.data());
      for (std::size_t t = 0; t < out; ++t) {
        SiteOffset o;
        if (best_[t] != kNone) {
          const std::size_t s = std::size_t(from_[t]);
          const auto& xy = pass_y_offset_[(s * out + y) * out + x];
          o = {xy[0], xy[1], std::int8_t(int(s) - (w + int(t)))};
        }
        result[(t * out + y) * out + x] = o;
      }
    }
  }
}

void ChunkReach::compute(const std::vector<bool>& wanted, int bricks, int window) {
  // In span coordinates a brick b's cells are [8 b + window, 8 b + 7 +
  // window] and it reads [8 b, 8 b + 7 + 2 window]: the bricks reading
  // position p are those with 8 b in [p - 7 - 2 window, p].
  bricks_ = bricks;
  span_ = bricks * kBrickCells + 2 * window;
  const std::size_t n = std::size_t(bricks);
  const std::size_t span = std::size_t(span_);
  first_.resize(span);
  last_.resize(span);
  for (int p = 0; p < span_; ++p) {
    const int lo = p - 7 - 2 * window;
    first_[std::size_t(p)] = lo <= 0 ? 0 : (lo + kBrickCells - 1) / kBrickCells;
    last_[std::size_t(p)] = std::min(p / kBrickCells, bricks - 1);
  }
  // Per slab (x brick) a 2D prefix count of the wanted bricks over (y, z)
  // bricks, and per column (x, y brick) a 1D one over z bricks: then
  // whether any wanted brick reads a place is one rectangle's count.
  const std::size_t side = n + 1;
  slab_count_.assign(n * side * side, 0);
  column_count_.assign(n * n * side, 0);
  for (std::size_t bx = 0; bx < n; ++bx) {
    for (std::size_t bz = 0; bz < n; ++bz) {
      for (std::size_t by = 0; by < n; ++by) {
        const int here = wanted[(bz * n + by) * n + bx] ? 1 : 0;
        slab_count_[(bx * side + bz + 1) * side + by + 1] = here + slab_count_[(bx * side + bz) * side + by + 1] +
                                                           slab_count_[(bx * side + bz + 1) * side + by] -
                                                           slab_count_[(bx * side + bz) * side + by];
        column_count_[(bx * n + by) * side + bz + 1] = column_count_[(bx * n + by) * side + bz] + here;
      }
    }
  }
  // The 2D tables the passes read per place (one byte each).
  slab_rows_.assign(n * span * span, 0);
  rows_.assign(span * span, 0);
  slab_z_.assign(n * span, 0);
  column_z_.assign(n * n * span, 0);
  for (std::size_t z = 0; z < span; ++z) {
    const int z0 = first_[z], z1 = last_[z];
    if (z0 > z1) continue;
    for (std::size_t bx = 0; bx < n; ++bx) {
      const auto count = [&](int y0, int y1) {
        const std::size_t b = bx * side;
        return slab_count_[(b + std::size_t(z1) + 1) * side + std::size_t(y1) + 1] -
               slab_count_[(b + std::size_t(z0)) * side + std::size_t(y1) + 1] -
               slab_count_[(b + std::size_t(z1) + 1) * side + std::size_t(y0)] +
               slab_count_[(b + std::size_t(z0)) * side + std::size_t(y0)];
      };
      if (count(0, bricks - 1) == 0) continue;
      slab_z_[bx * span + z] = 1;
      for (std::size_t y = 0; y < span; ++y) {
        if (first_[y] > last_[y] || count(first_[y], last_[y]) == 0) continue;
        slab_rows_[(bx * span + z) * span + y] = 1;
        rows_[z * span + y] = 1;
      }
      for (std::size_t by = 0; by < n; ++by) {
        const std::size_t c = (bx * n + by) * side;
        column_z_[(bx * n + by) * span + z] = column_count_[c + std::size_t(z1) + 1] != column_count_[c + std::size_t(z0)];
      }
    }
  }
}

void ChunkTransform::run(BrickIndex first, SiteLookup sites, FunctionRef<bool(BrickIndex)> wanted,
                         FunctionRef<void(BrickIndex, const BrickOffsets&)> write, int kinds) {
  // Which bricks are wanted; the y and z passes skip the columns of none.
  std::vector<bool> wanted_brick(std::size_t(bricks_) * std::size_t(bricks_) * std::size_t(bricks_));
  wanted_xy_.assign(std::size_t(bricks_) * std::size_t(bricks_), false);
  bool any = false;
  for (std::uint32_t bz = 0; bz < std::uint32_t(bricks_); ++bz) {
    for (std::uint32_t by = 0; by < std::uint32_t(bricks_); ++by) {
      for (std::uint32_t bx = 0; bx < std::uint32_t(bricks_); ++bx) {
        if (!wanted(BrickIndex{first.x + bx, first.y + by, first.z + bz})) continue;
        wanted_brick[(bz * std::uint32_t(bricks_) + by) * std::uint32_t(bricks_) + bx] = true;
        wanted_xy_[bx + std::size_t(bricks_) * by] = true;
        any = true;
      }
    }
  }
  if (!any) return;
  reach_.compute(wanted_brick, bricks_, window_);
  load_sites(first, sites);
  if ((kinds & 1) != 0) transform(0);
  if ((kinds & 2) != 0) transform(1);
  BrickOffsets offsets;
  const std::size_t out = std::size_t(out_);
  for (std::uint32_t bz = 0; bz < std::uint32_t(bricks_); ++bz) {
    for (std::uint32_t by = 0; by < std::uint32_t(bricks_); ++by) {
      for (std::uint32_t bx = 0; bx < std::uint32_t(bricks_); ++bx) {
        const BrickIndex brick{first.x + bx, first.y + by, first.z + bz};
        if (!wanted_brick[(bz * std::uint32_t(bricks_) + by) * std::uint32_t(bricks_) + bx]) continue;
        for (int i = 0; i < kBrickVolume; ++i) {
          const std::size_t x = bx * kBrickCells + std::size_t(i & 7);
          const std::size_t y = by * kBrickCells + std::size_t((i >> 3) & 7);
          const std::size_t z = bz * kBrickCells + std::size_t(i >> 6);
          const std::size_t at = (z * out + y) * out + x;
          offsets[std::size_t(i)] = {result_[0][at], result_[1][at]};
        }
        write(brick, offsets);
      }
    }
  }
}

}  // namespace umbra::detail
