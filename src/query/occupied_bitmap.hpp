// OccupiedBitmap: one bit per finest voxel of a box of keys, set for the
// occupied ones; what the occlusion sweep reads instead of the tree.
//
// Layout: x-rows of 64-bit words, rows ordered by y then z:
//   word (z * ny + y) * words_per_row + (x - x0) / 64, bit (x - x0) % 64.
// A run of up to 64 voxels along x is read with two words and a shift.
// Voxels outside the box read as not occupied (callers only rely on bits
// to prove that something is blocked, so a missing bit is safe).
// Cost: reset() clears nx * ny * nz / 8 bytes (the previous capacity is
// kept); set_box() touches the words of the box.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "umbra/core/morton.hpp"

namespace umbra::detail {

class OccupiedBitmap {
 public:
  /// Covers keys low..high (inclusive) on every axis; all bits clear.
  void reset(Key low, Key high);
  /// The bytes reset(low, high) allocates.
  [[nodiscard]] static std::uint64_t bytes_for(Key low, Key high);
  /// Sets the bits of the keys low..high, clipped to the box.
  void set_box(Key low, Key high);

  [[nodiscard]] bool occupied(std::int64_t x, std::int64_t y, std::int64_t z) const {
    if (!inside(x, y, z)) return false;
    const std::int64_t dx = x - low_[0];
    return (words_[row_index(y, z) + std::size_t(dx >> 6)] >> (dx & 63)) & 1u;
  }
  /// Bits of the voxels x0 .. x0 + count - 1 of row (y, z), voxel x0 in bit 0 (count <= 64).
  [[nodiscard]] std::uint64_t row(std::int64_t x0, int count, std::int64_t y, std::int64_t z) const;

 private:
  [[nodiscard]] bool inside(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return x >= low_[0] && x <= high_[0] && y >= low_[1] && y <= high_[1] && z >= low_[2] && z <= high_[2];
  }
  [[nodiscard]] std::size_t row_index(std::int64_t y, std::int64_t z) const {
    return (std::size_t(z - low_[2]) * std::size_t(high_[1] - low_[1] + 1) + std::size_t(y - low_[1])) *
           words_per_row_;
  }
  std::int64_t low_[3] = {0, 0, 0};
  std::int64_t high_[3] = {-1, -1, -1};
  std::size_t words_per_row_ = 0;
  std::vector<std::uint64_t> words_;
};

}  // namespace umbra::detail
