// The color samples of a scan, found with any number of threads, are those
// of a brute-force reference: every point in the map (and the box) that
// gives a hit, stably sorted by voxel. Few voxels get many points, so every
// part of the parallel steps begins inside a voxel, and the maximum range
// cuts through the voxels, so which point of a voxel decides matters.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/thread_pool.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/color_samples.hpp"
#include "ray/ray_direction.hpp"

namespace umbra {
namespace {

using Sample = OccupancyTree::ColorSample;

std::vector<Sample> reference(const Grid& grid, Vec3f origin, const std::vector<Vec3f>& points,
                              const std::vector<Rgb>& colors, const InsertOptions& options,
                              const std::optional<KeyBox>& box) {
  struct Found {
    std::uint64_t code;
    std::size_t point;
  };
  std::vector<Found> found;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::optional<Key> key = grid.key_checked(points[i]);
    if (key && (!box || box->contains(*key))) found.push_back({morton::encode(*key), i});
  }
  std::stable_sort(found.begin(), found.end(), [](const Found& a, const Found& b) { return a.code < b.code; });
  const auto within = [&](Vec3f end) {
    return options.max_range <= 0.0 || octomap_norm(end - origin) <= options.max_range;
  };
  std::vector<Sample> samples;
  for (std::size_t i = 0; i < found.size(); ++i) {
    // The voxel's first point in scan order: the first of its run.
    std::size_t first = i;
    while (first > 0 && found[first - 1].code == found[i].code) --first;
    bool hit = false;
    switch (options.integrator) {
      case IntegratorKind::simple: hit = within(points[found[i].point]); break;
      case IntegratorKind::discrete: hit = within(grid.center_f(morton::decode(found[i].code))); break;
      default: hit = within(points[found[first].point]); break;
    }
    if (hit) samples.push_back({found[i].code, colors[found[i].point]});
  }
  return samples;
}

bool same(const std::vector<Sample>& a, const std::vector<Sample>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const Sample& x, const Sample& y) { return x.code == y.code && x.rgb == y.rgb; });
}

TEST(ColorSamples, AnyNumberOfThreadsGivesTheReferenceSamples) {
  const Grid grid(0.1, 16);
  const Vec3f origin{0.0f, 0.0f, 0.0f};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Vec3f> points;
  std::vector<Rgb> colors;
  // 20000 points in about 40 voxels around 1 m, the maximum range.
  for (int i = 0; i < 20000; ++i) {
    if (i % 997 == 0) {
      points.push_back({NAN, 0.0f, 0.0f});
    } else if (i % 1009 == 0) {
      points.push_back({1e9f, 0.0f, 0.0f});
    } else {
      points.push_back({1.0f + 0.1f * u(rng), 0.15f * u(rng), 0.15f * u(rng)});
    }
    const auto byte = [&] { return static_cast<std::uint8_t>(rng()); };
    colors.push_back({byte(), byte(), byte()});
  }
  std::vector<std::uint64_t> codes(points.size());
  voxel_codes(grid, points, codes.data());
  ThreadPool two(2);
  ThreadPool three(3);
  ThreadPool eight(8);
  const KeyBox box{grid.key(Vec3d{0.95, -0.1, -0.2}), grid.key(Vec3d{1.2, 0.2, 0.2})};
  for (const IntegratorKind kind : {IntegratorKind::simple, IntegratorKind::discrete, IntegratorKind::fast}) {
    for (const std::optional<KeyBox>& in_box : {std::optional<KeyBox>{}, std::optional<KeyBox>{box}}) {
      SCOPED_TRACE(std::string(to_string(kind)) + (in_box ? " in a box" : ""));
      InsertOptions options;
      options.integrator = kind;
      options.max_range = 1.0;
      const std::vector<Sample> expected = reference(grid, origin, points, colors, options, in_box);
      ASSERT_GT(expected.size(), 1000u);
      ASSERT_LT(expected.size(), points.size() - 1000) << "the maximum range drops points";
      for (ThreadPool* pool : {static_cast<ThreadPool*>(nullptr), &two, &three, &eight}) {
        SCOPED_TRACE(pool == nullptr ? 1u : pool->size());
        EXPECT_TRUE(same(color_samples(grid, origin, points, colors, options, in_box, pool), expected));
        // The same with the codes given (as the projective integrator gives its image's).
        EXPECT_TRUE(same(color_samples(grid, origin, points, colors, options, in_box, pool, codes), expected));
      }
    }
  }
}

}  // namespace
}  // namespace umbra
