#include "query/occupied_bitmap.hpp"

namespace umbra::detail {

void OccupiedBitmap::reset(Key low, Key high) {
  for (int a = 0; a < 3; ++a) {
    low_[a] = low[a];
    high_[a] = high[a];
  }
  words_per_row_ = std::size_t((high_[0] - low_[0]) / 64 + 1);
  const std::size_t rows = std::size_t(high_[1] - low_[1] + 1) * std::size_t(high_[2] - low_[2] + 1);
  words_.assign(rows * words_per_row_, 0);
}

std::uint64_t OccupiedBitmap::bytes_for(Key low, Key high) {
  const std::uint64_t words_per_row = (std::uint64_t{high.x} - low.x) / 64 + 1;
  const std::uint64_t rows = (std::uint64_t{high.y} - low.y + 1) * (std::uint64_t{high.z} - low.z + 1);
  return words_per_row * rows * sizeof(std::uint64_t);
}

void OccupiedBitmap::set_box(Key low, Key high) {
  const std::int64_t x0 = std::max<std::int64_t>(low.x, low_[0]);
  const std::int64_t x1 = std::min<std::int64_t>(high.x, high_[0]);
  const std::int64_t y0 = std::max<std::int64_t>(low.y, low_[1]);
  const std::int64_t y1 = std::min<std::int64_t>(high.y, high_[1]);
  const std::int64_t z0 = std::max<std::int64_t>(low.z, low_[2]);
  const std::int64_t z1 = std::min<std::int64_t>(high.z, high_[2]);
  if (x0 > x1 || y0 > y1 || z0 > z1) return;
  for (std::int64_t z = z0; z <= z1; ++z) {
    for (std::int64_t y = y0; y <= y1; ++y) {
      std::uint64_t* row = &words_[row_index(y, z)];
      for (std::int64_t x = x0 - low_[0]; x <= x1 - low_[0];) {
        // Whole words at a time where the run allows.
        const std::int64_t bit = x & 63;
        const std::int64_t count = std::min<std::int64_t>(64 - bit, x1 - low_[0] - x + 1);
        const std::uint64_t mask = count == 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << count) - 1) << bit;
        row[x >> 6] |= mask;
        x += count;
      }
    }
  }
}

std::uint64_t OccupiedBitmap::row(std::int64_t x0, int count, std::int64_t y, std::int64_t z) const {
  if (y < low_[1] || y > high_[1] || z < low_[2] || z > high_[2]) return 0;
  const std::uint64_t* words = &words_[row_index(y, z)];
  const std::int64_t last_word = std::int64_t(words_per_row_) - 1;
  auto word = [&](std::int64_t i) { return i < 0 || i > last_word ? std::uint64_t{0} : words[i]; };
  // Bit positions relative to the box; x0 may lie before it.
  const std::int64_t start = x0 - low_[0];
  const std::int64_t index = start >= 0 ? start >> 6 : -((-start + 63) >> 6);
  const std::int64_t shift = start - index * 64;  // 0..63
  std::uint64_t bits = word(index) >> shift;
  if (shift != 0) bits |= word(index + 1) << (64 - shift);
  // Bits past the box's last voxel are zero already; keep only `count`.
  return count >= 64 ? bits : bits & ((std::uint64_t{1} << count) - 1);
}

}  // namespace umbra::detail
