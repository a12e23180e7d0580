// The moving window against brute force. The brute force is a map without a
// window that is cropped (crop_map, tested on its own) to the window's box
// before every scan, the box computed here from the rule in
// docs/design.md ("A map that moves"); the map with the window must equal
// it voxel for voxel, everywhere, after every scan, with automatic pruning
// on and off. Also: what scans observe outside the box is clipped; memory
// stays bounded over a long drive; the pieces a spill receives, merged with
// what the window holds, give the map without a window; a spill that
// throws leaves the map unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "support/map_internals.hpp"
#include "support/query_oracle.hpp"
#include "umbra/map/map_crop.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

/// The window's box by the documented rule, computed apart from the library.
VoxelBox expected_box(const Grid& grid, Vec3d robot, double half_extent, int step_depth) {
  const Key key = grid.key(robot);
  const std::int64_t step = std::int64_t{1} << step_depth;
  const auto steps = static_cast<std::int64_t>(std::ceil(half_extent / (grid.resolution() * static_cast<double>(step))));
  const std::int64_t keys = grid.keys_per_axis();
  VoxelBox box;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t centre = key[axis] / step;
    box.lo[axis] = static_cast<std::uint32_t>(std::max<std::int64_t>(0, (centre - steps) * step));
    box.hi[axis] = static_cast<std::uint32_t>(std::min<std::int64_t>(keys - 1, (centre + steps + 1) * step - 1));
  }
  return box;
}

/// A scan from `origin` with points up to `reach` metres away on each axis.
std::vector<Vec3f> scan_around(Vec3d origin, double reach, std::mt19937& random, int count = 60) {
  std::uniform_real_distribution<double> offset(-reach, reach);
  std::vector<Vec3f> points;
  for (int i = 0; i < count; ++i) {
    points.push_back(Vec3f(Vec3d{origin.x + offset(random), origin.y + offset(random), origin.z + offset(random)}));
  }
  return points;
}

/// A robot path through the map (depth 5, 0.2 m: +-3.2 m), out and back so
/// that places leave the box and come back into it.
/// (As floats, what the scans' origins are.)
std::vector<Vec3d> drive() {
  std::vector<Vec3d> path;
  for (int i = 0; i <= 24; ++i) path.push_back({-2.0 + 0.17 * i, -1.0 + 0.05 * i, 0.1 * std::sin(i)});
  for (int i = 24; i >= 0; --i) path.push_back({-2.0 + 0.17 * i, 0.6 - 0.03 * i, 0.3});
  for (Vec3d& p : path) p = Vec3d(Vec3f(p));
  return path;
}

void expect_same_voxels(const OccupancyMap& map, const OccupancyMap& reference, const VoxelBox& box, int scan) {
  ASSERT_EQ(test::check_invariants(map), "") << "scan " << scan;
  const test::DenseValues got(map);
  const test::DenseValues want(reference);
  for (std::uint32_t z = 0; z < got.size(); ++z) {
    for (std::uint32_t y = 0; y < got.size(); ++y) {
      for (std::uint32_t x = 0; x < got.size(); ++x) {
        const Key key{x, y, z};
        if (!box.contains(key)) {
          ASSERT_EQ(got.at(key), 0.0f) << "outside the box, scan " << scan;
        }
        ASSERT_EQ(got.at(key), want.at(key)) << x << " " << y << " " << z << ", scan " << scan;
      }
    }
  }
}

TEST(MovingWindow, EqualsTheMapCroppedToTheBoxBeforeEveryScan) {
  for (const bool prune : {true, false}) {
    for (const int step_depth : {1, 2}) {
      SCOPED_TRACE(testing::Message() << "prune " << prune << ", step depth " << step_depth);
      const double half_extent = 0.8;
      OccupancyMap map(0.2, 5);
      OccupancyMap reference(0.2, 5);
      map.set_auto_prune(prune);
      reference.set_auto_prune(prune);
      MovingWindow window;
      window.half_extent = half_extent;
      window.step_depth = step_depth;
      map.set_moving_window(window);
      std::mt19937 random(7);
      int scan = 0;
      std::size_t moves = 0;
      std::optional<VoxelBox> last;
      for (const Vec3d robot : drive()) {
        // Every point within half_extent of the robot lies in the box.
        const std::vector<Vec3f> points = scan_around(robot, half_extent * 0.99, random);
        const VoxelBox box = expected_box(map.grid(), robot, half_extent, step_depth);
        if (last != box) ++moves;
        last = box;
        reference = crop_map(reference, box);
        reference.insert_point_cloud(Vec3f(robot), points);
        map.insert_point_cloud(Vec3f(robot), points);
        ASSERT_EQ(map.window_box(), box) << "scan " << scan;
        expect_same_voxels(map, reference, box, scan);
        ++scan;
      }
      EXPECT_GT(moves, 10u) << "the box hardly moved: a weak test";
    }
  }
}

TEST(MovingWindow, ClipsWhatScansObserveOutsideTheBox) {
  for (const bool prune : {true, false}) {
    OccupancyMap map(0.2, 5);
    OccupancyMap reference(0.2, 5);
    map.set_auto_prune(prune);
    reference.set_auto_prune(prune);
    MovingWindow window;
    window.half_extent = 0.6;
    window.step_depth = 2;
    map.set_moving_window(window);
    std::mt19937 random(3);
    int scan = 0;
    for (const Vec3d robot : drive()) {
      const std::vector<Vec3f> points = scan_around(robot, 2.5, random);  // far past the box
      const VoxelBox box = expected_box(map.grid(), robot, window.half_extent, window.step_depth);
      // The rule: a scan is clipped as by set_bounding_box with the box's
      // faces pulled in by a millionth of a voxel.
      const double inset = 1e-6 * map.resolution();
      const Vec3d lo = map.grid().min_corner(box.lo);
      const Vec3d hi = map.grid().min_corner(box.hi);
      const double edge = map.resolution() - inset;
      reference = crop_map(reference, box);
      reference.set_bounding_box(Aabb{{lo.x + inset, lo.y + inset, lo.z + inset}, {hi.x + edge, hi.y + edge, hi.z + edge}});
      reference.insert_point_cloud(Vec3f(robot), points);
      map.insert_point_cloud(Vec3f(robot), points);
      expect_same_voxels(map, reference, box, scan);
      ++scan;
    }
  }
}

TEST(MovingWindow, MemoryStaysBoundedOverALongDrive) {
  OccupancyMap map(0.1, 8);  // +-12.8 m
  OccupancyMap full(0.1, 8);
  MovingWindow window;
  window.half_extent = 1.0;
  window.step_depth = 2;
  map.set_moving_window(window);
  std::mt19937 random(5);
  std::size_t most_nodes = 0;
  std::size_t most_bytes = 0;
  std::size_t bytes_after_first_lap = 0;
  for (int lap = 0; lap < 2; ++lap) {
    for (int i = 0; i < 110; ++i) {
      const Vec3d robot(Vec3f(Vec3d{-11.0 + 0.2 * i, 0.05 * (i % 7), 0.0}));
      const std::vector<Vec3f> points = scan_around(robot, 0.99, random, 200);
      map.insert_point_cloud(Vec3f(robot), points);
      full.insert_point_cloud(Vec3f(robot), points);
      most_nodes = std::max(most_nodes, map.node_counts().total());
      most_bytes = std::max(most_bytes, map.memory_bytes());
    }
    if (lap == 0) bytes_after_first_lap = most_bytes;
  }
  // The box is at most 6 steps of 4 voxels = 24 voxels a side: even fully
  // known to the finest voxel it holds at most 24^3 * 8 / 7 nodes, plus the
  // cut nodes above it.
  const std::size_t bound = 24 * 24 * 24 * 8 / 7 + 8 * 8 * 8;
  EXPECT_LE(most_nodes, bound);
  EXPECT_GT(full.node_counts().total(), 3 * bound) << "the drive is too short to tell";
  ASSERT_EQ(test::check_invariants(map), "");
  // The freed nodes are reused: the second lap needs hardly more (the
  // integrator's buffers vary with the scans).
  EXPECT_LE(most_bytes, bytes_after_first_lap + bytes_after_first_lap / 10);
}

TEST(MovingWindow, SpilledPiecesAndTheWindowAddUpToTheWholeMap) {
  for (const bool prune : {true, false}) {
    // A clamping range no voxel reaches: the sums are then the whole map's.
    SensorModel sensor;
    sensor.clamp_min = 1e-20;
    sensor.clamp_max = 1.0 - 1e-12;
    OccupancyMap map(0.1, 6, sensor);
    OccupancyMap whole(0.1, 6, sensor);
    map.set_auto_prune(prune);
    std::vector<OccupancyMap> pieces;
    MovingWindow window;
    window.half_extent = 0.7;
    window.step_depth = 1;
    window.spill = [&](const OccupancyMap& leaving) {
      ASSERT_EQ(test::check_invariants(leaving), "");
      // What leaves lies outside the box the window moves to... and was in the map.
      pieces.push_back(leaving);
    };
    map.set_moving_window(window);
    std::mt19937 random(9);
    for (const Vec3d robot : drive()) {
      const std::vector<Vec3f> points = scan_around(robot, 0.69, random);
      map.insert_point_cloud(Vec3f(robot), points);
      whole.insert_point_cloud(Vec3f(robot), points);
    }
    ASSERT_GT(pieces.size(), 10u);
    OccupancyMap assembled(0.1, 6, sensor);
    for (const OccupancyMap& piece : pieces) assembled.merge(piece);
    assembled.merge(map);
    const test::DenseValues got(assembled);
    const test::DenseValues want(whole);
    std::size_t known = 0;
    std::size_t exact = 0;
    for (std::uint32_t z = 0; z < got.size(); ++z) {
      for (std::uint32_t y = 0; y < got.size(); ++y) {
        for (std::uint32_t x = 0; x < got.size(); ++x) {
          const Key key{x, y, z};
          // Sums of the same steps in another order: equal up to float rounding.
          ASSERT_NEAR(got.at(key), want.at(key), 1e-4f) << x << " " << y << " " << z;
          ASSERT_EQ(got.at(key) == 0.0f, want.at(key) == 0.0f) << x << " " << y << " " << z;
          known += want.at(key) != 0.0f ? 1 : 0;
          exact += want.at(key) != 0.0f && got.at(key) == want.at(key) ? 1 : 0;
        }
      }
    }
    EXPECT_GT(known, 1000u);
    EXPECT_GT(exact, known / 2) << "most voxels are seen in one stay only and must be exact";
  }
}

TEST(MovingWindow, ASpillThatThrowsLeavesTheMapUnchanged) {
  OccupancyMap map(0.1, 6);
  MovingWindow window;
  window.half_extent = 0.5;
  window.step_depth = 1;
  bool fail = false;
  window.spill = [&](const OccupancyMap&) {
    if (fail) throw std::runtime_error("disk full");
  };
  map.set_moving_window(window);
  std::mt19937 random(1);
  map.insert_point_cloud(Vec3f(Vec3d{0.0, 0.0, 0.0}), scan_around({0.0, 0.0, 0.0}, 0.49, random));
  const std::optional<VoxelBox> box = map.window_box();
  const test::DenseValues before(map);
  fail = true;
  const Vec3d far{1.5, 0.0, 0.0};
  EXPECT_THROW(map.insert_point_cloud(Vec3f(far), scan_around(far, 0.4, random)), std::runtime_error);
  EXPECT_THROW(map.move_window(far), std::runtime_error);
  EXPECT_EQ(map.window_box(), box);
  const test::DenseValues after(map);
  for (std::uint32_t z = 0; z < after.size(); ++z) {
    for (std::uint32_t y = 0; y < after.size(); ++y) {
      for (std::uint32_t x = 0; x < after.size(); ++x) ASSERT_EQ(after.at({x, y, z}), before.at({x, y, z}));
    }
  }
  fail = false;
  EXPECT_TRUE(map.move_window(far).spilled);
}

TEST(MovingWindow, RefusesBadSettingsAndMisuse) {
  OccupancyMap map(0.1, 6);
  EXPECT_THROW(map.move_window({0.0, 0.0, 0.0}), std::logic_error);
  MovingWindow window;
  EXPECT_THROW(map.set_moving_window(window), std::invalid_argument);  // half_extent 0
  window.half_extent = std::nan("");
  EXPECT_THROW(map.set_moving_window(window), std::invalid_argument);
  window.half_extent = 1.0;
  window.step_depth = 6;
  EXPECT_THROW(map.set_moving_window(window), std::invalid_argument);
  window.step_depth = -1;
  map.set_moving_window(window);
  EXPECT_EQ(window.step_depth_on(map.grid()), 1);  // 0.2 m <= 1.0 / 4 < 0.4 m
  EXPECT_THROW(map.move_window({100.0, 0.0, 0.0}), std::out_of_range);
  EXPECT_FALSE(map.window_box().has_value());
  EXPECT_TRUE(map.move_window({0.0, 0.0, 0.0}).moved);
  EXPECT_FALSE(map.move_window({0.05, 0.0, 0.0}).moved);  // the same step
}

}  // namespace
}  // namespace umbra
