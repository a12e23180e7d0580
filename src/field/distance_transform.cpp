#include "field/distance_transform.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace umbra::detail {
namespace {
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
}

ChunkTransform::ChunkTransform(const FieldLayout& layout)
    : layout_(layout),
      window_(layout.window()),
      bricks_(chunk_bricks(layout.window())),
      out_(chunk_bricks(layout.window()) * kBrickCells),
      span_(out_ + 2 * layout.window()),
      e2_(2u << layout.depth()) {
  const std::size_t span = std::size_t(span_);
  const std::size_t out = std::size_t(out_);
  sites_.resize(span * span * span);
  pass_x_.resize(span * span * out);
  column_.resize(span);
  pass_y_.resize(span * out * out);
  pass_y_offset_.resize(pass_y_.size());
  for (auto& r : result_) r.resize(out * out * out);
  hull_.resize(span);
  bounds_.resize(span + 1);
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
        const BrickBits& bits = *sites(BrickIndex{std::uint32_t(bx), std::uint32_t(by), std::uint32_t(bz)});
        const std::int64_t base[3] = {bx * kBrickCells - origin[0], by * kBrickCells - origin[1],
                                      bz * kBrickCells - origin[2]};
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
  const int w = window_;
  const double cap = std::floor(double(layout_.max_distance()) * 2.0 / layout_.resolution() *
                                double(layout_.max_distance()) * 2.0 / layout_.resolution());
  // The site at the cell itself.
  for (int t = 0; t < out_; ++t) {
    const std::uint32_t v = values[std::size_t(w + t) * stride];
    best[t] = v;
    from[t] = std::int16_t(v == kNone ? -1 : w + t);
  }
  const double e2 = double(e2_);
  for (const double shift : {e2 - 1.0, 1.0 - e2}) {  // sites before the cell, then after it
    int k = -1;
    for (int s = 0; s < span_; ++s) {
      const std::uint32_t v = values[std::size_t(s) * stride];
      if (v == kNone) continue;
      const double c = e2 * s + shift;
      const double f = double(v) + c * c;
      double start = -std::numeric_limits<double>::infinity();
      while (k >= 0) {
        const int q = hull_[std::size_t(k)];
        const double cq = e2 * q + shift;
        const double fq = double(values[std::size_t(q) * stride]) + cq * cq;
        start = (f - fq) / (2.0 * (c - cq));
        if (start > bounds_[std::size_t(k)]) break;
        --k;
        start = -std::numeric_limits<double>::infinity();
      }
      ++k;
      hull_[std::size_t(k)] = s;
      bounds_[std::size_t(k)] = start;
    }
    if (k < 0) continue;
    int j = 0;
    for (int t = 0; t < out_; ++t) {
      const double x = e2 * (w + t);
      while (j < k && bounds_[std::size_t(j + 1)] <= x) ++j;
      const int s = hull_[std::size_t(j)];
      // The site's true term (the parabola overestimates the other side's).
      const std::int64_t n = std::abs(std::int64_t(w + t) - s);
      const double gap = n == 0 ? 0.0 : double(n - 1) * e2 + 1.0;
      const double total = double(values[std::size_t(s) * stride]) + gap * gap;
      if (total < double(best[t])) {
        best[t] = total > cap ? kNone - 1 : std::uint32_t(total);
        from[t] = std::int16_t(s);
      }
    }
  }
  // Beyond the cap nothing counts (and the offsets then fit the window).
  for (int t = 0; t < out_; ++t) {
    if (best[t] != kNone && double(best[t]) > cap) {
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
  // Pass x: nearest site along each row, for the output columns.
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t y = 0; y < span; ++y) {
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
  // Pass y: along each column of the output's x, all z.
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t x = 0; x < out; ++x) {
      if (!wanted_x_[x / kBrickCells]) continue;  // no wanted brick in this slab
      for (std::size_t y = 0; y < span; ++y) {
        const std::int8_t dx = pass_x_[(z * span + y) * out + x];
        column_[y] = dx == SiteOffset::kNoSite ? kNone : layout_.squared_gap(dx);
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
      if (!wanted_xy_[x / kBrickCells + std::size_t(bricks_) * (y / kBrickCells)]) continue;
      for (std::size_t z = 0; z < span; ++z) column_[z] = pass_y_[(z * out + y) * out + x];
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

void ChunkTransform::run(BrickIndex first, SiteLookup sites, FunctionRef<bool(BrickIndex)> wanted,
                         FunctionRef<void(BrickIndex, const BrickOffsets&)> write, int kinds) {
  // Which bricks are wanted; the y and z passes skip the columns of none.
  std::vector<bool> wanted_brick(std::size_t(bricks_) * std::size_t(bricks_) * std::size_t(bricks_));
  wanted_x_.assign(std::size_t(bricks_), false);
  wanted_xy_.assign(std::size_t(bricks_) * std::size_t(bricks_), false);
  bool any = false;
  for (std::uint32_t bz = 0; bz < std::uint32_t(bricks_); ++bz) {
    for (std::uint32_t by = 0; by < std::uint32_t(bricks_); ++by) {
      for (std::uint32_t bx = 0; bx < std::uint32_t(bricks_); ++bx) {
        if (!wanted(BrickIndex{first.x + bx, first.y + by, first.z + bz})) continue;
        wanted_brick[(bz * std::uint32_t(bricks_) + by) * std::uint32_t(bricks_) + bx] = true;
        wanted_x_[bx] = true;
        wanted_xy_[bx + std::size_t(bricks_) * by] = true;
        any = true;
      }
    }
  }
  if (!any) return;
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
