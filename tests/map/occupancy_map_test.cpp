// OccupancyMap: the user-facing API, its errors and its statistics.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "support/map_internals.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

template <typename Exception, typename Action>
std::string message_of(Action&& action) {
  try {
    action();
  } catch (const Exception& e) {
    return e.what();
  }
  return "no exception";
}

TEST(OccupancyMap, ConstructionValidatesEveryParameter) {
  EXPECT_NE(message_of<std::invalid_argument>([] { OccupancyMap(0.0); }).find("resolution"), std::string::npos);
  EXPECT_NE(message_of<std::invalid_argument>([] { OccupancyMap(0.1, 25); }).find("depth_levels"), std::string::npos);
  EXPECT_NE(message_of<std::invalid_argument>([] { OccupancyMap(0.1, 16, SensorModel{0.3, 0.4, 0.1, 0.9}); })
                .find("p_hit"),
            std::string::npos);
  EXPECT_NE(message_of<std::invalid_argument>([] { OccupancyMap(0.1, 16, {}, Thresholds{0.4, 0.6}); })
                .find("free threshold"),
            std::string::npos);
  const OccupancyMap map(MapConfig{0.2, 12, SensorModel{0.8, 0.3, 0.2, 0.9}, Thresholds{0.6, 0.4}});
  EXPECT_EQ(map.config().resolution, 0.2);
  EXPECT_EQ(map.config().depth_levels, 12);
  EXPECT_EQ(map.config().sensor, (SensorModel{0.8, 0.3, 0.2, 0.9}));
  EXPECT_EQ(map.config().thresholds, (Thresholds{0.6, 0.4}));
}

TEST(OccupancyMap, SingleVoxelUpdatesAndQueriesAtEveryDepth) {
  OccupancyMap map(0.1);
  const Vec3d wall{1.05, 2.05, 0.35};
  map.update_hit(wall);
  map.update_miss({1.15, 2.05, 0.35});
  EXPECT_EQ(map.state(wall), OccupancyState::occupied);
  EXPECT_EQ(map.state({1.15, 2.05, 0.35}), OccupancyState::free);
  EXPECT_EQ(map.state({5.0, 5.0, 5.0}), OccupancyState::unknown);
  EXPECT_NEAR(map.occupancy(wall), 0.7, 1e-6);
  EXPECT_NEAR(map.occupancy({1.15, 2.05, 0.35}), 0.4, 1e-6);
  // The 0.2 m node holding both: occupied (max), contains free and unknown.
  EXPECT_EQ(map.state(wall, 1), OccupancyState::occupied);
  EXPECT_TRUE(map.contains_occupied(wall, 1));
  EXPECT_TRUE(map.contains_free({1.15, 2.05, 0.35}, 1));
  EXPECT_TRUE(map.contains_unknown(wall, 1));
  EXPECT_FALSE(map.contains_free(wall, 0));
  EXPECT_EQ(map.state(wall, 16), OccupancyState::occupied) << "the root knows about the obstacle";
  map.set_log_odds(wall, -1.0f);
  EXPECT_EQ(map.state(wall), OccupancyState::free);
  EXPECT_FALSE(map.contains_occupied(wall, 16));
  map.set_log_odds(wall, 100.0f);
  EXPECT_EQ(map.log_odds(wall), map.sensor_model().clamp_max_log_odds()) << "set clamps";
}

// A braced coordinate must mean a coordinate (Vec3d), not be ambiguous with
// the Key overloads; a Key must mean that key.
TEST(OccupancyMap, BracedCoordinatesAndKeysReachTheSameVoxel) {
  MapConfig config;
  config.resolution = 0.1;
  config.color = true;
  OccupancyMap map(config);
  const Key key = map.key({1.05, 2.05, 0.35});
  map.set_log_odds({1.05, 2.05, 0.35}, 0.5f);
  EXPECT_EQ(map.log_odds(Vec3d{1.05, 2.05, 0.35}), 0.5f);
  map.update_log_odds(key, 0.25f);
  EXPECT_EQ(map.log_odds({1.05, 2.05, 0.35}), 0.75f);
  map.update_log_odds({1.05, 2.05, 0.35}, 0.25f);
  map.set_log_odds(Key{key.x + 1, key.y, key.z}, -0.5f);
  EXPECT_EQ(map.log_odds({1.15, 2.05, 0.35}), -0.5f);
  EXPECT_EQ(map.log_odds({1.05, 2.05, 0.35}), 1.0f);
  map.add_color({1.05, 2.05, 0.35}, Rgb{10, 20, 30});
  EXPECT_EQ(map.color({1.05, 2.05, 0.35}), (Rgb{10, 20, 30}));
  EXPECT_EQ(map.color(key), (Rgb{10, 20, 30}));
  EXPECT_EQ(map.color({1.15, 2.05, 0.35}), std::nullopt);
}

TEST(OccupancyMap, BadCoordinatesDepthsAndValuesAreErrors) {
  OccupancyMap map(0.1, 8);  // [-12.8, 12.8)
  EXPECT_NE(message_of<std::out_of_range>([&] { map.update_hit({13.0, 0.0, 0.0}); }).find("outside the map"),
            std::string::npos);
  EXPECT_THROW((void)map.state({0, 0, -20.0}), std::out_of_range);
  EXPECT_THROW((void)map.state({std::numeric_limits<double>::quiet_NaN(), 0, 0}), std::out_of_range);
  EXPECT_NE(message_of<std::out_of_range>([&] { (void)map.state({0, 0, 0}, 9); }).find("depth 9"), std::string::npos);
  EXPECT_THROW((void)map.state({0, 0, 0}, -1), std::out_of_range);
  EXPECT_THROW(map.update_log_odds(Vec3d{0, 0, 0}, std::numeric_limits<float>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(map.set_log_odds(Vec3d{0, 0, 0}, std::numeric_limits<float>::infinity()), std::invalid_argument);
  EXPECT_THROW((void)map.node(Key{256, 0, 0}), std::out_of_range);
  EXPECT_EQ(map.node_counts().total(), 1u) << "failed calls change nothing";
}

TEST(OccupancyMap, InsertPointCloudCountsWhatItSkips) {
  OccupancyMap map(0.1, 8);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Vec3f> points = {
      {2.0f, 0.0f, 0.0f},  {0.0f, 2.0f, 0.0f}, {nan, 0.0f, 0.0f},
      {0.0f, std::numeric_limits<float>::infinity(), 0.0f},
      {50.0f, 0.0f, 0.0f},                         // outside the map
      {0.0f, 0.0f, 9.0f},                          // beyond max range: truncated at 5 m
  };
  InsertOptions options;
  options.max_range = 5.0;
  const InsertStats stats = map.insert_point_cloud({0, 0, 0}, points, options);
  EXPECT_EQ(stats.points, 6u);
  EXPECT_EQ(stats.non_finite, 2u);
  EXPECT_EQ(stats.hits, 2u);
  EXPECT_EQ(stats.truncated, 2u) << "the 50 m point is beyond max range too";
  EXPECT_EQ(stats.out_of_bounds, 0u);
  EXPECT_EQ(map.state({2.0, 0.0, 0.0}), OccupancyState::occupied);
  EXPECT_EQ(map.state({1.0, 0.0, 0.0}), OccupancyState::free);
  EXPECT_EQ(map.state({0.0, 0.0, 4.85}), OccupancyState::free);
  EXPECT_EQ(map.state({0.0, 0.0, 5.15}), OccupancyState::unknown) << "cut at max range, no hit";
  EXPECT_EQ(map.state({0.0, 0.0, 9.05}), OccupancyState::unknown);

  const InsertStats unlimited = map.insert_point_cloud({0, 0, 0}, std::vector<Vec3f>{{50.0f, 0.0f, 0.0f}});
  EXPECT_EQ(unlimited.out_of_bounds, 1u);
  EXPECT_EQ(unlimited.rays, 0u);
}

TEST(OccupancyMap, BadOriginIsAnErrorAndChangesNothing) {
  OccupancyMap map(0.1, 8);
  const std::vector<Vec3f> points = {{1.0f, 0.0f, 0.0f}};
  EXPECT_THROW(map.insert_point_cloud({20.0f, 0.0f, 0.0f}, points), std::out_of_range);
  EXPECT_THROW(map.insert_point_cloud({std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f}, points),
               std::invalid_argument);
  InsertOptions bad;
  bad.max_range = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(map.insert_point_cloud({0, 0, 0}, points, bad), std::invalid_argument);
  EXPECT_EQ(map.node_counts().total(), 1u);
}

TEST(OccupancyMap, ThresholdsChangeAtRunTime) {
  OccupancyMap map(0.1);
  map.update_hit({0.05, 0.05, 0.05});  // p = 0.7
  map.update_miss({0.15, 0.05, 0.05});  // p = 0.4
  map.set_thresholds({0.8, 0.3});
  EXPECT_EQ(map.state({0.05, 0.05, 0.05}), OccupancyState::unknown);
  EXPECT_EQ(map.state({0.15, 0.05, 0.05}), OccupancyState::unknown);
  EXPECT_FALSE(map.contains_free({0.0, 0.0, 0.0}, 5));
  EXPECT_FALSE(map.contains_occupied({0.0, 0.0, 0.0}, 5));
  map.set_thresholds({0.6, 0.45});
  EXPECT_EQ(map.state({0.05, 0.05, 0.05}), OccupancyState::occupied);
  EXPECT_TRUE(map.contains_free({0.0, 0.0, 0.0}, 5));
  EXPECT_THROW(map.set_thresholds({0.4, 0.6}), std::invalid_argument);
  EXPECT_EQ(map.thresholds(), (Thresholds{0.6, 0.45}));
}

TEST(OccupancyMap, LeavesCoverEveryKnownVoxelOnce) {
  OccupancyMap map(0.1, 10);
  std::vector<Vec3f> points;
  for (int i = 0; i < 200; ++i) {
    const double angle = i * 0.0314;
    points.push_back({static_cast<float>(3.0 * std::cos(angle)), static_cast<float>(3.0 * std::sin(angle)), 0.5f});
  }
  map.insert_point_cloud({0, 0, 0.5f}, points);
  std::size_t occupied = 0;
  std::size_t free = 0;
  std::uint64_t previous_end = 0;
  map.for_each_leaf([&](const Node& leaf) {
    const std::uint64_t first = morton::encode(leaf.key);
    EXPECT_GE(first, previous_end) << "Morton order, no overlap";
    previous_end = first + (std::uint64_t{1} << (3 * leaf.depth));
    const std::size_t voxels = std::size_t{1} << (3 * leaf.depth);
    if (leaf.state == OccupancyState::occupied) occupied += voxels;
    if (leaf.state == OccupancyState::free) free += voxels;
  });
  EXPECT_EQ(previous_end, std::uint64_t{1} << 30) << "the leaves tile the whole map";
  EXPECT_GE(occupied, 150u);
  EXPECT_GT(free, 1000u);
  EXPECT_GT(map.memory_bytes(), test::tree_of(map).memory_bytes());
}

}  // namespace
}  // namespace umbra

namespace umbra {
namespace {

/// compute_statistics the plain way: every known leaf's box in metres, through the public API.
MapStatistics statistics_leaf_by_leaf(const OccupancyMap& map) {
  MapStatistics stats;
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.state == OccupancyState::unknown) return;
    (leaf.state == OccupancyState::occupied ? stats.occupied_voxels : stats.free_voxels) += std::uint64_t{1}
                                                                                             << (3 * leaf.depth);
    const Vec3d low = map.grid().min_corner(leaf.key, leaf.depth);
    const double size = map.grid().node_size(leaf.depth);
    const Vec3d high = low + Vec3d{size, size, size};
    for (int axis = 0; axis < 3; ++axis) {
      stats.known_min[axis] = stats.has_known_space ? std::min(stats.known_min[axis], low[axis]) : low[axis];
      stats.known_max[axis] = stats.has_known_space ? std::max(stats.known_max[axis], high[axis]) : high[axis];
    }
    stats.has_known_space = true;
  });
  return stats;
}

TEST(OccupancyMap, StatisticsAgreeWithALeafByLeafCount) {
  // An odd resolution, so that metres round; free inner leaves of several
  // depths (pruned free space) and the extremes on different depths.
  OccupancyMap map(0.07, 16);
  EXPECT_FALSE(compute_statistics(map).has_known_space);
  std::vector<Vec3f> points;
  for (int i = 0; i < 400; ++i) {
    const float a = 0.0157f * static_cast<float>(i);
    points.push_back({3.1f * std::cos(a), 2.3f * std::sin(a), -1.3f + 0.01f * static_cast<float>(i)});
  }
  map.insert_point_cloud({0.2f, -0.4f, 0.1f}, points);
  map.set_log_odds(Vec3d{-9.0, 4.0, 7.5}, 3.0f);    // occupied, far from the rest
  map.set_log_odds(Vec3d{6.0, -8.0, -5.25}, -1.5f);  // a lone free voxel
  const MapStatistics fast = compute_statistics(map);
  const MapStatistics plain = statistics_leaf_by_leaf(map);
  ASSERT_TRUE(fast.has_known_space);
  EXPECT_GT(map.node_counts().inner_leaf, 100u);
  EXPECT_EQ(fast.occupied_voxels, plain.occupied_voxels);
  EXPECT_EQ(fast.free_voxels, plain.free_voxels);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_EQ(fast.known_min[axis], plain.known_min[axis]) << "axis " << axis;
    EXPECT_EQ(fast.known_max[axis], plain.known_max[axis]) << "axis " << axis;
  }
  EXPECT_EQ(fast.known_min.x, map.grid().min_corner(*map.grid().key_checked(Vec3d{-9.0, 4.0, 7.5})).x);
  EXPECT_EQ(fast.known_max.y, map.grid().min_corner(*map.grid().key_checked(Vec3d{-9.0, 4.0, 7.5})).y + 0.07);
  EXPECT_DOUBLE_EQ(fast.free_volume_m3, static_cast<double>(plain.free_voxels) * 0.07 * 0.07 * 0.07);
}

TEST(OccupancyMap, NarrowingTheClampingRangeClampsStoredValues) {
  OccupancyMap map(0.1);
  for (int i = 0; i < 10; ++i) map.update_hit({0.05, 0.05, 0.05});
  for (int i = 0; i < 10; ++i) map.update_miss({0.15, 0.05, 0.05});
  const SensorModel narrow{0.7, 0.4, 0.3, 0.8};
  map.set_sensor_model(narrow);
  EXPECT_EQ(map.log_odds({0.05, 0.05, 0.05}), narrow.clamp_max_log_odds());
  EXPECT_EQ(map.log_odds({0.15, 0.05, 0.05}), narrow.clamp_min_log_odds());
  EXPECT_EQ(map.log_odds({0.05, 0.05, 0.05}, 16), narrow.clamp_max_log_odds()) << "inner maxima follow";
  EXPECT_EQ(test::check_invariants(map), "");
  EXPECT_THROW(map.set_sensor_model(SensorModel{0.7, 0.4, 0.6, 0.8}), std::invalid_argument);
}

}  // namespace
}  // namespace umbra

#include <malloc.h>

#include <cstddef>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define UMBRA_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define UMBRA_SANITIZER_ALLOCATOR 1
#endif
#endif

#if defined(UMBRA_SANITIZER_ALLOCATOR)
// From the sanitizers' allocator interface (sanitizer/allocator_interface.h, which GCC does not install).
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#endif

namespace umbra {
namespace {

/// Bytes the heap holds for the program. Under a sanitizer malloc is the
/// sanitizer's, which does not feed mallinfo2: ask it instead.
std::size_t heap_bytes_in_use() {
#if defined(UMBRA_SANITIZER_ALLOCATOR)
  return __sanitizer_get_current_allocated_bytes();
#else
  const struct mallinfo2 info = ::mallinfo2();
  return info.uordblks + info.hblkhd;  // small chunks + mmapped chunks
#endif
}

TEST(OccupancyMap, ReportedMemoryIsWhatTheHeapReallyHolds) {
  std::vector<Vec3f> points;
  for (int i = 0; i < 20000; ++i) {
    const double a = i * 0.000314;
    const double b = (i % 100) * 0.01;
    points.push_back({static_cast<float>(8.0 * std::cos(a * 10)), static_cast<float>(8.0 * std::sin(a * 10)),
                      static_cast<float>(-1.0 + 2.0 * b)});
  }
  const std::size_t before = heap_bytes_in_use();
  if (before == 0) GTEST_SKIP() << "this allocator reports no statistics (neither mallinfo2 nor a sanitizer's)";
  auto map = std::make_unique<OccupancyMap>(0.05);
  map->insert_point_cloud({0, 0, 0}, points);
  const std::size_t reported = map->memory_bytes();
  const std::size_t held = heap_bytes_in_use() - before;
  // The heap also holds malloc's per-chunk headers and page rounding (at
  // most a page per block of thousands of groups), nothing else.
  EXPECT_GT(reported, 1'000'000u);
  EXPECT_NEAR(static_cast<double>(held), static_cast<double>(reported), 0.01 * static_cast<double>(reported))
      << "reported " << reported << " bytes, the heap holds " << held;
}

}  // namespace
}  // namespace umbra
