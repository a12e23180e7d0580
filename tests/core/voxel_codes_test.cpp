// voxel_codes: every implementation gives, bit for bit, the code of
// Grid::key_checked + morton::encode, and the two "no voxel" codes for
// points that are not finite or outside the map, on random points heavy in
// the cases where rounding decides: voxel borders, the map's faces, negative
// coordinates, and every count modulo the AVX2 step of four points.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/voxel_codes.hpp"

namespace umbra {
namespace {

std::uint64_t expected_code(const Grid& grid, Vec3f p) {
  if (!p.is_finite()) return kNonFiniteCode;
  const std::optional<Key> key = grid.key_checked(p);
  return key ? morton::encode(*key) : kOutsideCode;
}

/// One coordinate: mostly on or one float step off a voxel border (anywhere
/// in the map), else uniform over a range a little wider than the map, at
/// the map's faces, or not finite.
float random_coordinate(const Grid& grid, std::mt19937& rng) {
  const double half = grid.half_extent();
  std::uniform_int_distribution<int> kind(0, 19);
  std::uniform_int_distribution<std::int64_t> key(-std::int64_t{grid.key_offset()} - 2,
                                                  std::int64_t{grid.key_offset()} + 2);
  std::uniform_real_distribution<double> anywhere(-1.1 * half, 1.1 * half);
  std::uniform_real_distribution<double> near_origin(-std::min(5.0, half), std::min(5.0, half));
  const float border = static_cast<float>(double(key(rng)) * grid.resolution());
  switch (kind(rng)) {
    case 0: return std::numeric_limits<float>::quiet_NaN();
    case 1: return std::numeric_limits<float>::infinity();
    case 2: return -std::numeric_limits<float>::infinity();
    case 3: return static_cast<float>(half);   // just outside
    case 4: return static_cast<float>(-half);  // the first voxel
    case 5: return std::nextafter(static_cast<float>(half), 0.0f);
    case 6: return std::nextafter(static_cast<float>(-half), -1e30f);
    case 7: return static_cast<float>(anywhere(rng));
    case 8: return -0.0f;
    case 9: return std::numeric_limits<float>::denorm_min() * (rng() % 2 == 0 ? 1.0f : -1.0f);
    case 10: case 11: return static_cast<float>(near_origin(rng));
    case 12: case 13: return std::nextafter(border, 1e30f);
    case 14: case 15: return std::nextafter(border, -1e30f);
    default: return border;
  }
}

std::vector<Vec3f> random_points(const Grid& grid, std::size_t count, std::mt19937& rng) {
  std::vector<Vec3f> points(count);
  for (Vec3f& p : points) p = {random_coordinate(grid, rng), random_coordinate(grid, rng), random_coordinate(grid, rng)};
  return points;
}

std::vector<Grid> grids() {
  // Resolutions whose inverse is inexact too (0.3, 0.02), the finest and
  // coarsest maps, and the depths where keys need 1 and 21 bits.
  return {Grid(0.02, 16), Grid(0.05, 16), Grid(0.3, 16), Grid(0.1, 1), Grid(1e-4, 21), Grid(1e3, 21), Grid(0.07, 9)};
}

using VoxelCodes = void (*)(const Grid&, std::span<const Vec3f>, std::uint64_t*);

void expect_same_codes_as_grid(VoxelCodes voxel_codes_of, const char* name) {
  std::mt19937 rng(9);
  for (const Grid& grid : grids()) {
    SCOPED_TRACE(testing::Message() << name << ", resolution " << grid.resolution() << ", depth "
                                    << grid.depth_levels());
    for (std::size_t count = 0; count < 12; ++count) {  // every tail after steps of four
      const std::vector<Vec3f> points = random_points(grid, count, rng);
      std::vector<std::uint64_t> codes(count + 1, 42);
      voxel_codes_of(grid, points, codes.data());
      for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(codes[i], expected_code(grid, points[i])) << "point " << i;
      EXPECT_EQ(codes[count], 42u) << "wrote past the end";
    }
    const std::vector<Vec3f> points = random_points(grid, 20000, rng);
    std::vector<std::uint64_t> codes(points.size());
    voxel_codes_of(grid, points, codes.data());
    std::size_t wrong = 0;
    std::size_t with_voxel = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::uint64_t expected = expected_code(grid, points[i]);
      with_voxel += expected < kOutsideCode;
      if (codes[i] != expected && ++wrong <= 5) {
        ADD_FAILURE() << "point " << i << " (" << points[i].x << ", " << points[i].y << ", " << points[i].z
                      << "): code " << codes[i] << ", expected " << expected;
      }
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_GT(with_voxel, points.size() / 25);  // the inputs are not all rejected (4% in the two-voxel map)
  }
}

TEST(VoxelCodes, ScalarGivesTheGridsCodes) {
  expect_same_codes_as_grid(detail::voxel_codes_scalar, "scalar");
}

TEST(VoxelCodes, Avx2GivesTheGridsCodes) {
  if (!detail::voxel_codes_avx2_available()) GTEST_SKIP() << "no AVX2 on this CPU or build";
  expect_same_codes_as_grid(detail::voxel_codes_avx2, "avx2");
}

TEST(VoxelCodes, DispatchGivesTheGridsCodes) {
  expect_same_codes_as_grid(voxel_codes, "voxel_codes");
}

TEST(VoxelCodes, PointsWithoutVoxelGetCodesAboveEveryVoxel) {
  EXPECT_GT(kOutsideCode, morton::encode({(1u << 21) - 1, (1u << 21) - 1, (1u << 21) - 1}));
  EXPECT_NE(kOutsideCode, kNonFiniteCode);
}

}  // namespace
}  // namespace umbra
