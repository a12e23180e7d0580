#include "field/distance_transform.hpp"

#include <algorithm>
#include <limits>

namespace umbra::detail {
namespace {
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
}

ChunkTransform::ChunkTransform(const FieldLayout& layout)
    : layout_(layout), window_(layout.window()), span_(kChunkCells + 2 * layout.window()) {
  const std::size_t span = std::size_t(span_);
  sites_.resize(span * span * span);
  pass_x_.resize(span * span * kChunkCells);
  pass_y_.resize(span * kChunkCells * kChunkCells);
  pass_y_offset_.resize(pass_y_.size());
  for (auto& r : result_) r.resize(std::size_t(kChunkCells) * kChunkCells * kChunkCells);
}

void ChunkTransform::load_sites(BrickIndex first, SiteLookup sites, const BrickBits& absent_sites) {
  // Input cells [first * 8 - window, first * 8 + 32 + window) per axis;
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
  for (std::int64_t bz = brick_lo[2]; bz <= brick_hi[2]; ++bz) {
    for (std::int64_t by = brick_lo[1]; by <= brick_hi[1]; ++by) {
      for (std::int64_t bx = brick_lo[0]; bx <= brick_hi[0]; ++bx) {
        const BrickIndex b{std::uint32_t(bx), std::uint32_t(by), std::uint32_t(bz)};
        const BrickBits* bits = sites(b);
        if (bits == nullptr) bits = &absent_sites;
        for (int i = 0; i < kBrickVolume; ++i) {
          const int value = int(bits->is_occupied(i)) | (int(bits->is_unknown(i)) << 1);
          if (value == 0) continue;
          const std::int64_t x = bx * kBrickCells + (i & 7) - origin[0];
          const std::int64_t y = by * kBrickCells + ((i >> 3) & 7) - origin[1];
          const std::int64_t z = bz * kBrickCells + (i >> 6) - origin[2];
          if (x < 0 || y < 0 || z < 0 || x >= span_ || y >= span_ || z >= span_) continue;
          sites_[(std::size_t(z) * std::size_t(span_) + std::size_t(y)) * std::size_t(span_) + std::size_t(x)] =
              std::uint8_t(value);
        }
      }
    }
  }
}

void ChunkTransform::transform(int kind) {
  const std::uint8_t mask = std::uint8_t(1u << kind);
  const int w = window_;
  const std::size_t span = std::size_t(span_);
  constexpr std::size_t out = kChunkCells;
  // Pass x: nearest site along each row, for the output columns.
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t y = 0; y < span; ++y) {
      const std::uint8_t* row = &sites_[(z * span + y) * span];
      std::int8_t* dest = &pass_x_[(z * span + y) * out];
      // Nearest site at or before each x, then at or after it.
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
  // Pass y: best over the window of (x term + y term).
  for (std::size_t z = 0; z < span; ++z) {
    for (std::size_t y = 0; y < out; ++y) {
      for (std::size_t x = 0; x < out; ++x) {
        std::uint32_t best = kNone;
        std::array<std::int8_t, 2> best_offset{SiteOffset::kNoSite, 0};
        for (int t = 0; t <= w; ++t) {
          const std::uint32_t term = layout_.squared_gap(t);
          if (term >= best) break;
          for (int sign = -1; sign <= 1; sign += 2) {
            if (t == 0 && sign > 0) break;
            const std::size_t yy = std::size_t(int(y) + w + sign * t);
            const std::int8_t dx = pass_x_[(z * span + yy) * out + x];
            if (dx == SiteOffset::kNoSite) continue;
            const std::uint32_t s = layout_.squared_gap(dx) + term;
            if (s < best) {
              best = s;
              best_offset = {dx, std::int8_t(sign * t)};
            }
          }
        }
        pass_y_[(z * out + y) * out + x] = best;
        pass_y_offset_[(z * out + y) * out + x] = best_offset;
      }
    }
  }
  // Pass z: the same along z, then the cap.
  std::vector<SiteOffset>& result = result_[std::size_t(kind)];
  for (std::size_t z = 0; z < out; ++z) {
    for (std::size_t y = 0; y < out; ++y) {
      for (std::size_t x = 0; x < out; ++x) {
        std::uint32_t best = kNone;
        SiteOffset best_offset;
        for (int t = 0; t <= w; ++t) {
          const std::uint32_t term = layout_.squared_gap(t);
          if (term >= best) break;
          for (int sign = -1; sign <= 1; sign += 2) {
            if (t == 0 && sign > 0) break;
            const std::size_t zz = std::size_t(int(z) + w + sign * t);
            const std::size_t at = (zz * out + y) * out + x;
            if (pass_y_[at] == kNone) continue;
            const std::uint32_t s = pass_y_[at] + term;
            if (s < best) {
              best = s;
              best_offset = {pass_y_offset_[at][0], pass_y_offset_[at][1], std::int8_t(sign * t)};
            }
          }
        }
        result[(z * out + y) * out + x] = layout_.within_cap(best) && best != kNone ? best_offset : SiteOffset{};
      }
    }
  }
}

void ChunkTransform::run(BrickIndex first, SiteLookup sites, const BrickBits& absent_sites,
                         FunctionRef<bool(BrickIndex)> wanted, FunctionRef<void(BrickIndex, const BrickOffsets&)> write) {
  load_sites(first, sites, absent_sites);
  transform(0);
  transform(1);
  BrickOffsets offsets;
  for (std::uint32_t bz = 0; bz < kChunkBricks; ++bz) {
    for (std::uint32_t by = 0; by < kChunkBricks; ++by) {
      for (std::uint32_t bx = 0; bx < kChunkBricks; ++bx) {
        const BrickIndex brick{first.x + bx, first.y + by, first.z + bz};
        if (!wanted(brick)) continue;
        for (int i = 0; i < kBrickVolume; ++i) {
          const std::size_t x = bx * kBrickCells + std::size_t(i & 7);
          const std::size_t y = by * kBrickCells + std::size_t((i >> 3) & 7);
          const std::size_t z = bz * kBrickCells + std::size_t(i >> 6);
          const std::size_t at = (z * kChunkCells + y) * kChunkCells + x;
          offsets[std::size_t(i)] = {result_[0][at], result_[1][at]};
        }
        write(brick, offsets);
      }
    }
  }
}

}  // namespace umbra::detail
