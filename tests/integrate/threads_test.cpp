// Insertion with several threads gives exactly the map of one thread, for
// every integrator, with colour and with a bounding box. The parallel paths
// covered: end voxels found and sorted per part and merged, the hits added
// while the rays are grouped, the rays traced per worker, the batches
// merged, the tree updated in parallel.
#include <cstdlib>
#include <random>

#include <gtest/gtest.h>

#include "support/map_internals.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

struct Leaf {
  std::uint64_t code;
  int depth;
  std::uint32_t bits;
  std::optional<Rgb> color;
  friend bool operator==(const Leaf&, const Leaf&) = default;
};

std::vector<Leaf> contents(const OccupancyMap& map) {
  std::vector<Leaf> out;
  map.for_each_leaf([&](const Node& l) {
    out.push_back({morton::encode(l.key), l.depth, std::bit_cast<std::uint32_t>(l.log_odds), l.color});
  });
  return out;
}

TEST(Threads, EveryThreadCountBuildsTheSameMap) {
  struct Case {
    IntegratorKind kind;
    int clear_depth;  // 5: 1.6 m nodes, split below the clear depth as at millimetre resolutions
  };
  for (const auto [kind, clear_depth] : {Case{IntegratorKind::simple, -1}, Case{IntegratorKind::discrete, -1},
                                         Case{IntegratorKind::fast, -1}, Case{IntegratorKind::fast, 5}}) {
    for (const int variant : {0, 1, 2}) {
      // 0: plain (the tree is updated in parallel too), 1: with a box, 2: with colour.
      const bool with_box = variant == 1;
      const bool with_color = variant == 2;
      SCOPED_TRACE(std::string(to_string(kind)) + " clear depth " + std::to_string(clear_depth) + (with_box ? " with box" : "") + (with_color ? " with colour" : ""));
      std::vector<std::vector<Leaf>> results;
      // Under ThreadSanitizer (tests/map/run_tsan_stress.sh sets UMBRA_TSAN)
      // every access costs ~10x: fewer threads, the same code paths.
      const std::vector<unsigned> counts =
          std::getenv("UMBRA_TSAN") != nullptr ? std::vector<unsigned>{1u, 3u} : std::vector<unsigned>{1u, 2u, 3u, 8u};
      for (const unsigned threads : counts) {
        MapConfig config{0.05, 12, SensorModel{}, Thresholds{}, with_color};
        OccupancyMap map(config);
        if (with_box) map.set_bounding_box(Aabb{{-2.0, -1.5, -1.0}, {1.7, 2.2, 1.3}});
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        InsertOptions options;
        options.integrator = kind;
        options.threads = threads;
        options.max_range = 4.0;
        options.fine_steps = 1;
        options.clear_depth = clear_depth;
        for (int scan = 0; scan < 3; ++scan) {
          std::vector<Vec3f> points;
          std::vector<Rgb> colors;
          for (int i = 0; i < 3000; ++i) {
            // A box-shaped room with noise, and some far points.
            const float a = u(rng) * 3.14159f;
            const float r = i % 10 == 0 ? 6.0f : 3.0f + 0.05f * u(rng);
            points.push_back({r * std::cos(a), r * std::sin(a), 1.5f * u(rng)});
            colors.push_back({static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), 7});
          }
          // Points near the first ones again, at the end of the scan: their
          // voxels get points in the first and the last part of the scan
          // (whose end voxels are sorted on different threads and merged),
          // and the fast integrator's ray goes to the first point.
          for (int i = 0; i < 300; ++i) {
            points.push_back(points[static_cast<std::size_t>(i)] + Vec3f{0.01f * u(rng), 0.01f * u(rng), 0.01f * u(rng)});
            colors.push_back({static_cast<std::uint8_t>(rng()), 9, 7});
          }
          if (with_color) {
            map.insert_point_cloud({0.3f * scan, 0.1f, 0.0f}, points, colors, options);
          } else {
            map.insert_point_cloud({0.3f * scan, 0.1f, 0.0f}, points, options);
          }
        }
        ASSERT_EQ(test::check_invariants(map), "");
        results.push_back(contents(map));
      }
      EXPECT_GT(results[0].size(), 1000u);
      for (std::size_t i = 1; i < results.size(); ++i) EXPECT_TRUE(results[i] == results[0]) << "thread count #" << i;
    }
  }
}

}  // namespace
}  // namespace umbra
