// Keys and 64-bit Morton codes.
//
// A Key holds the integer voxel indices (x, y, z) at the finest depth, each in
// [0, 2^depth_levels). Its Morton code interleaves the bits as ...z1y1x1z0y0x0,
// so bits [3d, 3d+3) of a code are the child slot (x = 1, y = 2, z = 4, the
// same numbering as OctoMap) of the depth-d node on the path to the voxel, and
// sorting codes sorts voxels in depth-first tree order. 21 bits per axis fit
// in 63 bits, which bounds depth_levels to 21.
#pragma once

#include <bit>
#include <cstdint>

namespace umbra {

inline constexpr int kMaxDepthLevels = 21;

struct Key {
  std::uint32_t x = 0;
  std::uint32_t y = 0;
  std::uint32_t z = 0;

  constexpr std::uint32_t operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
  constexpr std::uint32_t& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }
  friend constexpr bool operator==(Key, Key) = default;

  /// The key of the depth-`depth` node that contains this finest-depth key.
  [[nodiscard]] constexpr Key at_depth(int depth) const { return {x >> depth, y >> depth, z >> depth}; }
};

namespace morton {

/// Bits of the x axis in a code; y is this << 1 and z this << 2.
inline constexpr std::uint64_t kAxisBits = 0x1249249249249249ULL;

/// Spreads the low 21 bits of v so that bit i lands on bit 3i.
constexpr std::uint64_t spread(std::uint32_t v) {
  std::uint64_t x = v & 0x1FFFFFu;
  x = (x | (x << 32)) & 0x001F00000000FFFFULL;
  x = (x | (x << 16)) & 0x001F0000FF0000FFULL;
  x = (x | (x << 8)) & 0x100F00F00F00F00FULL;
  x = (x | (x << 4)) & 0x10C30C30C30C30C3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}

/// Inverse of spread: gathers bits 0, 3, 6, ... into the low 21 bits.
constexpr std::uint32_t compact(std::uint64_t code) {
  std::uint64_t x = code & 0x1249249249249249ULL;
  x = (x | (x >> 2)) & 0x10C30C30C30C30C3ULL;
  x = (x | (x >> 4)) & 0x100F00F00F00F00FULL;
  x = (x | (x >> 8)) & 0x001F0000FF0000FFULL;
  x = (x | (x >> 16)) & 0x001F00000000FFFFULL;
  x = (x | (x >> 32)) & 0x1FFFFFULL;
  return static_cast<std::uint32_t>(x);
}

constexpr std::uint64_t encode(Key key) {
  return spread(key.x) | (spread(key.y) << 1) | (spread(key.z) << 2);
}

constexpr Key decode(std::uint64_t code) {
  return {compact(code), compact(code >> 1), compact(code >> 2)};
}

/// Child slot (0..7) of the depth-`depth` node on the path to `code`.
constexpr unsigned slot(std::uint64_t code, int depth) {
  return static_cast<unsigned>(code >> (3 * depth)) & 7u;
}

/// The code with its lowest 3*depth bits cleared: the first voxel of the depth-`depth` node.
constexpr std::uint64_t node_begin(std::uint64_t code, int depth) {
  return depth == 0 ? code : (code >> (3 * depth)) << (3 * depth);
}

/// Adds +1 to one axis of a code without decoding it (carries stay within that axis).
constexpr std::uint64_t increment(std::uint64_t code, int axis) {
  const std::uint64_t mask = kAxisBits << axis;
  return (((code | ~mask) + 1) & mask) | (code & ~mask);
}

/// Adds -1 to one axis of a code without decoding it.
constexpr std::uint64_t decrement(std::uint64_t code, int axis) {
  const std::uint64_t mask = kAxisBits << axis;
  return (((code & mask) - 1) & mask) | (code & ~mask);
}

/// Highest depth at which the paths to two codes differ (-1 when equal):
/// the groups at this depth and above are shared by both paths.
constexpr int highest_differing_depth(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t diff = a ^ b;
  return diff == 0 ? -1 : (63 - std::countl_zero(diff)) / 3;
}

}  // namespace morton
}  // namespace umbra
