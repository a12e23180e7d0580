// The sites of a distance field's brick, read from the map's tree: which of
// its 8^3 cells hold an occupied voxel, which an unknown one, and whether any
// holds known space. A childless coarse node fills its cells at once, so a
// large unknown or free node costs one visit, not one per voxel.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "field/field_layout.hpp"
#include "umbra/core/function_ref.hpp"

namespace umbra {
class OccupancyTree;
}

namespace umbra::detail {

struct BrickBits {
  std::array<std::uint64_t, 8> occupied{};  ///< bit i of word j: cell 64 j + i (cell_in_brick) is an occupied site
  std::array<std::uint64_t, 8> unknown{};
  bool known = false;  ///< some cell holds a free or occupied voxel

  [[nodiscard]] bool is_occupied(int cell) const { return (occupied[cell >> 6] >> (cell & 63) & 1u) != 0; }
  [[nodiscard]] bool is_unknown(int cell) const { return (unknown[cell >> 6] >> (cell & 63) & 1u) != 0; }
  /// A brick the map has never seen.
  static BrickBits all_unknown() {
    BrickBits b;
    b.unknown.fill(~std::uint64_t{0});
    return b;
  }
  friend bool operator==(const BrickBits&, const BrickBits&) = default;
};

/// Cells [min, max] per axis (inclusive) that a box-limited field sees.
struct CellBox {
  std::array<std::uint32_t, 3> min{};
  std::array<std::uint32_t, 3> max{};
  [[nodiscard]] bool contains(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
    return x >= min[0] && x <= max[0] && y >= min[1] && y <= max[1] && z >= min[2] && z <= max[2];
  }
};

/// The sites of brick `brick`; with `box`, cells outside it hold none.
BrickBits read_brick(const OccupancyTree& tree, const FieldLayout& layout, BrickIndex brick,
                     const std::optional<CellBox>& box);

/// Calls visit(brick) for every brick holding a known cell. Throws
/// std::length_error when there are more than `limit` of them.
void for_each_known_brick(const OccupancyTree& tree, const FieldLayout& layout, std::size_t limit,
                          FunctionRef<void(BrickIndex)> visit);

}  // namespace umbra::detail
