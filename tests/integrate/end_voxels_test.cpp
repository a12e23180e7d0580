// End voxels found part by part (one part per thread) and merged are those
// of the whole scan found at once: sorted, without repeats, each with the
// first point of the scan that fell in it, whatever the number of parts.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "integrate/end_voxels.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra {
namespace {

/// What the integrator did before the parts were sorted on their own: every
/// point's voxel, stably sorted, the first of each code kept.
std::vector<EndVoxel> whole_scan(const Grid& grid, const std::vector<Vec3f>& points) {
  std::vector<EndVoxel> voxels;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (auto key = grid.key_checked(points[i])) voxels.push_back({morton::encode(*key), i});
  }
  std::stable_sort(voxels.begin(), voxels.end(), [](const EndVoxel& a, const EndVoxel& b) { return a.code < b.code; });
  voxels.erase(std::unique(voxels.begin(), voxels.end(), [](const EndVoxel& a, const EndVoxel& b) { return a.code == b.code; }),
               voxels.end());
  return voxels;
}

TEST(EndVoxels, AnyNumberOfPartsGivesTheVoxelsOfTheWholeScan) {
  const Grid grid(0.1, 16);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Vec3f> points;
  // Few voxels for many points, so that most voxels get points in several
  // parts; some points repeat in a row, some are not finite or outside the map.
  for (int i = 0; i < 20000; ++i) {
    if (i % 997 == 0) {
      points.push_back({NAN, 0.0f, 0.0f});
    } else if (i % 1009 == 0) {
      points.push_back({1e9f, 0.0f, 0.0f});
    } else if (i % 5 == 0 && !points.empty()) {
      points.push_back(points.back());
    } else {
      points.push_back({u(rng), u(rng), 0.3f * u(rng)});
    }
  }
  const std::vector<EndVoxel> expected = whole_scan(grid, points);
  const auto non_finite = static_cast<std::size_t>(
      std::count_if(points.begin(), points.end(), [](const Vec3f& p) { return !p.is_finite(); }));
  const auto outside = static_cast<std::size_t>(std::count_if(
      points.begin(), points.end(), [&](const Vec3f& p) { return p.is_finite() && !grid.key_checked(p); }));
  ASSERT_GT(non_finite, 0u);
  ASSERT_GT(outside, 0u);
  ASSERT_GT(expected.size(), 500u);
  ASSERT_LT(expected.size(), 5000u);
  for (const std::size_t part_count : {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{8}}) {
    SCOPED_TRACE(part_count);
    std::vector<std::vector<EndVoxel>> parts(part_count);
    InsertStats stats;
    for (std::size_t p = 0; p < part_count; ++p) {
      const std::size_t begin = points.size() * p / part_count;
      const std::size_t end = points.size() * (p + 1) / part_count;
      end_voxels(grid, points, begin, end - begin, parts[p], stats);
    }
    EXPECT_EQ(stats.non_finite, non_finite);
    EXPECT_EQ(stats.out_of_bounds, outside);
    const std::vector<EndVoxel> merged = merge_end_voxels(parts);
    ASSERT_EQ(merged.size(), expected.size());
    for (std::size_t i = 0; i < merged.size(); ++i) {
      ASSERT_EQ(merged[i].code, expected[i].code) << i;
      ASSERT_EQ(merged[i].point, expected[i].point) << i;
    }
  }
}

}  // namespace
}  // namespace umbra
