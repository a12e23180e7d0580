// Insertion with several threads gives exactly the map of one thread, for
// every integrator, with colour and with a bounding box. The parallel paths
// covered: end voxels found and sorted per part and merged, the hits added
// while the rays are grouped, the rays traced per worker, the batches
// merged, the tree updated in parallel (with and without colour), the
// colour samples found, sorted and added to the tree in parallel.
#include <algorithm>
#include <bit>
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
  std::uint8_t color_weight;  // samples behind the colour
  friend bool operator==(const Leaf&, const Leaf&) = default;
};

/// Every childless node of the map's tree: value, colour and weight.
std::vector<Leaf> contents(const OccupancyMap& map) {
  std::vector<Leaf> out;
  const OccupancyTree& tree = test::tree_of(map);
  tree.for_each_leaf([&](NodeRef node, std::uint64_t code) {
    out.push_back({code, node.depth, std::bit_cast<std::uint32_t>(tree.log_odds(node)), tree.color(node),
                   tree.color_weight(node)});
  });
  return out;
}

/// The thread counts compared: more than this machine's cores among them.
std::vector<unsigned> thread_counts() {
  // Under ThreadSanitizer (tests/map/run_tsan_stress.sh sets UMBRA_TSAN)
  // every access costs ~10x: fewer threads, the same code paths.
  return std::getenv("UMBRA_TSAN") != nullptr ? std::vector<unsigned>{1u, 3u} : std::vector<unsigned>{1u, 2u, 3u, 8u};
}

TEST(Threads, EveryThreadCountBuildsTheSameMap) {
  struct Case {
    IntegratorKind kind;
    int clear_depth;  // 5: 1.6 m nodes, split below the clear depth as at millimetre resolutions
  };
  for (const auto [kind, clear_depth] : {Case{IntegratorKind::simple, -1}, Case{IntegratorKind::discrete, -1},
                                         Case{IntegratorKind::fast, -1}, Case{IntegratorKind::fast, 5}}) {
    for (const int variant : {0, 1, 2, 3}) {
      // 0: plain (the tree is updated in parallel too), 1: with a box, 2: with colour, 3: both.
      const bool with_box = variant == 1 || variant == 3;
      const bool with_color = variant >= 2;
      SCOPED_TRACE(std::string(to_string(kind)) + " clear depth " + std::to_string(clear_depth) + (with_box ? " with box" : "") + (with_color ? " with colour" : ""));
      std::vector<std::vector<Leaf>> results;
      for (const unsigned threads : thread_counts()) {
        MapConfig config{0.05, 12, SensorModel{}, Thresholds{}, with_color};
        OccupancyMap map(config);
        // Variant 1's box holds none of the walls, variant 3's part of them (colours there).
        if (variant == 1) map.set_bounding_box(Aabb{{-2.0, -1.5, -1.0}, {1.7, 2.2, 1.3}});
        if (variant == 3) map.set_bounding_box(Aabb{{-3.2, -1.5, -1.0}, {1.7, 3.2, 1.3}});
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

// A coloured map at 4 mm in a box: the parallel apply and colour walk split
// the tree far below the root, through inner leaves that earlier scans
// cleared whole, and every
// voxel gets several samples, some from the first and some from the last
// part of a scan (their order decides the blended colour). Clear depth 5
// (automatic: 12.8 cm nodes) clears nodes whole and splits them near the
// wall, 3 (3.2 cm) walks its rays through smaller nodes.
TEST(Threads, ColouredMapAtFineResolutionIsTheSameForEveryThreadCount) {
  // The first test covers every integrator with colour; this one the fast
  // integrator as it runs at millimetres (the discrete one walks every ray
  // voxel by voxel: seconds and 700 MB here).
  for (const int clear_depth : {-1, 3}) {
    SCOPED_TRACE("clear depth " + std::to_string(clear_depth));
    std::vector<std::vector<Leaf>> results;
    std::vector<NodeCounts> counts;
    for (const unsigned threads : thread_counts()) {
      SCOPED_TRACE(std::to_string(threads) + " threads");
      MapConfig config{0.004, 16, SensorModel{}, Thresholds{}, true};
      OccupancyMap map(config);
      map.set_bounding_box(Aabb{{-0.9, -0.7, -0.5}, {0.8, 0.9, 0.6}});
      std::mt19937 rng(3);
      std::uniform_real_distribution<float> u(-1.0f, 1.0f);
      InsertOptions options;
      options.integrator = IntegratorKind::fast;
      options.clear_depth = clear_depth;
      options.threads = threads;
      options.max_range = 1.2;
      options.fine_steps = 0;
      for (int scan = 0; scan < 3; ++scan) {
        const Vec3f origin{0.05f * scan, -0.04f * scan, 0.02f};
        std::vector<Vec3f> points;
        std::vector<Rgb> colors;
        for (int i = 0; i < 1000; ++i) {
          // A wall 1 m away, 2 cm thick (parts beyond the range and the box).
          const float a = u(rng) * 3.14159f;
          const float r = 1.0f + 0.01f * u(rng);
          points.push_back(origin + Vec3f{r * std::cos(a), r * std::sin(a), 0.4f * u(rng)});
          colors.push_back({static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), 3});
        }
        // Each point twice more, 1 mm off: three samples in most voxels (the
        // blend of three depends on their order), in different parts.
        for (int i = 0; i < 2000; ++i) {
          points.push_back(points[static_cast<std::size_t>(i % 1000)] + Vec3f{0.001f * u(rng), 0.001f * u(rng), 0.0f});
          colors.push_back({static_cast<std::uint8_t>(rng()), 5, static_cast<std::uint8_t>(rng())});
        }
        map.insert_point_cloud(origin, points, colors, options);
      }
      ASSERT_EQ(test::check_invariants(map), "");
      results.push_back(contents(map));
      counts.push_back(test::tree_of(map).count_nodes());
    }
    const auto weighed = std::count_if(results[0].begin(), results[0].end(),
                                       [](const Leaf& l) { return l.color_weight >= 3; });
    EXPECT_GT(weighed, 500) << "voxels with three colour samples or more";
    for (std::size_t i = 1; i < results.size(); ++i) {
      EXPECT_TRUE(results[i] == results[0]) << "thread count #" << i;
      EXPECT_EQ(counts[i].total(), counts[0].total()) << "thread count #" << i;
    }
  }
}

}  // namespace
}  // namespace umbra
