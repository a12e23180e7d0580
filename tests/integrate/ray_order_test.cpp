// The fast integrator's ray order (rays_in_end_order) is a stable sort of
// all rays by end code, however many parts the rays come in and however
// many of them moved (truncated or clipped ends give no hit and may lie
// anywhere; the others come in increasing order of their ends).
#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "integrate/ray_order.hpp"

namespace umbra {
namespace {

TEST(RayOrder, IsAStableSortOfAllRaysByEndCode) {
  std::mt19937 rng(5);
  for (const int moved_percent : {0, 10, 50, 100}) {
    // Rays that give a hit end in increasing codes; moved rays end anywhere,
    // often in a code some other ray ends in too (ties are kept in scan order).
    std::vector<PreparedRay> scan;
    std::uint64_t code = 0;
    for (std::uint32_t i = 0; i < 5000; ++i) {
      PreparedRay ray{};
      ray.begin_key = {i, 0, 0};  // tells the rays apart
      code += 1 + rng() % 3;
      ray.hit = static_cast<int>(rng() % 100) >= moved_percent;
      ray.end_code = ray.hit ? code : rng() % (code + 10);
      scan.push_back(ray);
    }
    std::vector<PreparedRay> expected = scan;
    std::stable_sort(expected.begin(), expected.end(),
                     [](const PreparedRay& a, const PreparedRay& b) { return a.end_code < b.end_code; });
    for (const std::size_t part_count : {std::size_t{1}, std::size_t{2}, std::size_t{7}}) {
      SCOPED_TRACE(std::to_string(moved_percent) + "% moved, " + std::to_string(part_count) + " parts");
      std::vector<std::vector<PreparedRay>> parts(part_count);
      for (std::size_t p = 0; p < part_count; ++p) {
        parts[p].assign(scan.begin() + static_cast<std::ptrdiff_t>(scan.size() * p / part_count),
                        scan.begin() + static_cast<std::ptrdiff_t>(scan.size() * (p + 1) / part_count));
      }
      const std::vector<PreparedRay> sorted = rays_in_end_order(parts, 48);
      ASSERT_EQ(sorted.size(), expected.size());
      for (std::size_t i = 0; i < sorted.size(); ++i) {
        ASSERT_EQ(sorted[i].end_code, expected[i].end_code) << i;
        ASSERT_EQ(sorted[i].begin_key, expected[i].begin_key) << i;
      }
    }
  }
}

}  // namespace
}  // namespace umbra
