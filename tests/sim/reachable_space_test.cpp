// Tests of the reachable-space ground truth on rooms small enough to count
// by hand: a closed 2 m cube, the cube split by a wall, the wall with a
// window; counts of boxes of cells; bad arguments. And on a 9 x 9 x 6 m part
// of the industrial plant, cell by cell against a brute force: the scene's
// own distance query at every cell centre and a plain flood fill.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <deque>
#include <stdexcept>
#include <vector>

#include "umbra/sim/industrial_scene.hpp"
#include "umbra/sim/reachable_space.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {
namespace {

constexpr double kCell = 0.1;
constexpr double kRadius = 0.27;  // no cell centre lies exactly at this distance from a wall below
const Box kRoom{{0, 0, 0}, {2, 2, 2}};

/// The inside of kRoom, closed by six 0.2 m slabs.
Scene closed_room() {
  Scene scene;
  scene.add_box({{-0.2, -0.2, -0.2}, {2.2, 2.2, 0.0}});
  scene.add_box({{-0.2, -0.2, 2.0}, {2.2, 2.2, 2.2}});
  scene.add_box({{-0.2, -0.2, 0.0}, {0.0, 2.2, 2.0}});
  scene.add_box({{2.0, -0.2, 0.0}, {2.2, 2.2, 2.0}});
  scene.add_box({{0.0, -0.2, 0.0}, {2.0, 0.0, 2.0}});
  scene.add_box({{0.0, 2.0, 0.0}, {2.0, 2.2, 2.0}});
  return scene;
}

TEST(ReachableSpace, ClosedRoomByHand) {
  // Cell centres lie at 0.05, 0.15, ..., 1.95 on each axis; those at least
  // 0.27 m from both walls are 0.35 ... 1.65: 14 per axis.
  const ReachableSpace space(closed_room(), kRoom, kCell, kRadius, {1.0, 1.0, 1.0});
  EXPECT_EQ(space.cell_count(), 14u * 14u * 14u);
  EXPECT_EQ(space.clear_cell_count(), 14u * 14u * 14u);
  EXPECT_NEAR(space.volume(), 2744 * 0.001, 1e-9);
  // Centres in [0, 1]^3: 0.35 ... 0.95, 7 per axis; one cell; a box outside.
  EXPECT_EQ(space.count_in({0, 0, 0}, {1, 1, 1}), 7u * 7u * 7u);
  EXPECT_EQ(space.count_in({0.3, 0.3, 0.3}, {0.4, 0.4, 0.4}), 1u);
  EXPECT_EQ(space.count_in({0.2, 0.2, 0.2}, {0.3, 0.3, 0.3}), 0u);
  EXPECT_EQ(space.count_in({-5, -5, -5}, {5, 5, 5}), 2744u);
  EXPECT_EQ(space.count_in({3, 3, 3}, {4, 4, 4}), 0u);
  EXPECT_TRUE(space.reachable({1.0, 1.0, 1.0}));
  EXPECT_TRUE(space.reachable({0.31, 1.69, 0.5}));   // cells of centres 0.35 and 1.65
  EXPECT_FALSE(space.reachable({0.29, 1.0, 1.0}));   // centre 0.25: too close to the wall
  EXPECT_FALSE(space.reachable({1.0, 1.0, 1.71}));
  EXPECT_FALSE(space.reachable({5.0, 1.0, 1.0}));    // outside the region
}

TEST(ReachableSpace, WallSplitsTheRoom) {
  // A wall x in [0.95, 1.05]: on the left centres 0.35 ... 0.65 (4), on the
  // right 1.35 ... 1.65 (4); both clear, only the start's side reachable.
  Scene scene = closed_room();
  scene.add_box({{0.95, 0.0, 0.0}, {1.05, 2.0, 2.0}});
  const ReachableSpace space(scene, kRoom, kCell, kRadius, {0.5, 1.0, 1.0});
  EXPECT_EQ(space.cell_count(), 4u * 14u * 14u);
  EXPECT_EQ(space.clear_cell_count(), 2u * 4u * 14u * 14u);
  EXPECT_TRUE(space.reachable({0.5, 1.0, 1.0}));
  EXPECT_FALSE(space.reachable({1.5, 1.0, 1.0}));
}

TEST(ReachableSpace, WindowJoinsTheHalves) {
  // The wall with a window y, z in [0.5, 1.5] (four boxes around it). Cells
  // of the window's layers that are clear, counted per layer:
  //  x = 0.95, 1.05 (in the wall): y, z at least 0.27 from 0.5 and 1.5:
  //    0.85 ... 1.15, 4 x 4;
  //  x = 0.85, 1.15 (0.1 from the wall): sqrt(0.1^2 + dy^2) >= 0.27 needs
  //    dy >= 0.251, so again 4 x 4;
  //  x = 0.75, 1.25 (0.2 from it): dy >= 0.181, so 0.75 ... 1.25, 6 x 6.
  // The rest is the two halves of the split room, all joined now.
  Scene scene = closed_room();
  scene.add_box({{0.95, 0.0, 0.0}, {1.05, 0.5, 2.0}});
  scene.add_box({{0.95, 1.5, 0.0}, {1.05, 2.0, 2.0}});
  scene.add_box({{0.95, 0.5, 0.0}, {1.05, 1.5, 0.5}});
  scene.add_box({{0.95, 0.5, 1.5}, {1.05, 1.5, 2.0}});
  const ReachableSpace space(scene, kRoom, kCell, kRadius, {0.5, 1.0, 1.0});
  const std::size_t halves = 2u * 4u * 14u * 14u;
  const std::size_t window = 4u * 16u + 2u * 36u;
  EXPECT_EQ(space.cell_count(), halves + window);
  EXPECT_EQ(space.clear_cell_count(), halves + window);
  EXPECT_EQ(space.count_in({0.9, 0, 0}, {1.1, 2, 2}), 2u * 16u);
  EXPECT_EQ(space.count_in({0.7, 0, 0}, {0.8, 2, 2}), 36u);
  EXPECT_TRUE(space.reachable({1.5, 1.0, 1.0}));
}

TEST(ReachableSpace, PartOfThePlantEqualsBruteForce) {
  const IndustrialPlant plant = make_industrial_scene(1);
  const double cell = 0.16;
  const double radius = 0.3;
  const Box region{plant.start - Vec3d{4.5, 4.5, 1.4}, plant.start + Vec3d{4.5, 4.5, 4.5}};
  const ReachableSpace space(plant.scene, region, cell, radius, plant.start);

  // Cells whose centres lie in the region, on the lattice i * cell.
  std::array<long, 3> first{};
  std::array<long, 3> size{};
  for (std::size_t a = 0; a < 3; ++a) {
    first[a] = long(std::ceil(region.min[a] / cell - 0.5));
    size[a] = long(std::floor(region.max[a] / cell - 0.5)) - first[a] + 1;
  }
  auto centre = [&](long i, long j, long k) {
    return Vec3d{(double(first[0] + i) + 0.5) * cell, (double(first[1] + j) + 0.5) * cell,
                 (double(first[2] + k) + 0.5) * cell};
  };
  auto index = [&](long i, long j, long k) { return std::size_t((k * size[1] + j) * size[0] + i); };
  std::vector<char> clear(std::size_t(size[0] * size[1] * size[2]), 0);
  std::vector<char> borderline(clear.size(), 0);
  for (long k = 0; k < size[2]; ++k) {
    for (long j = 0; j < size[1]; ++j) {
      for (long i = 0; i < size[0]; ++i) {
        const Vec3d c = centre(i, j, k);
        const double d = plant.scene.is_inside_solid(c) ? -1.0 : plant.scene.distance_to_nearest_surface(c);
        clear[index(i, j, k)] = d >= radius;
        borderline[index(i, j, k)] = std::abs(d - radius) < 1e-9;
      }
    }
  }
  std::vector<char> reached(clear.size(), 0);
  std::deque<std::array<long, 3>> queue;
  const long si = long(std::floor(plant.start.x / cell)) - first[0];
  const long sj = long(std::floor(plant.start.y / cell)) - first[1];
  const long sk = long(std::floor(plant.start.z / cell)) - first[2];
  ASSERT_TRUE(clear[index(si, sj, sk)]);
  reached[index(si, sj, sk)] = 1;
  queue.push_back({si, sj, sk});
  std::size_t count = 0;
  while (!queue.empty()) {
    const auto [i, j, k] = queue.front();
    queue.pop_front();
    ++count;
    const long steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : steps) {
      const long a = i + s[0], b = j + s[1], c = k + s[2];
      if (a < 0 || b < 0 || c < 0 || a >= size[0] || b >= size[1] || c >= size[2]) continue;
      if (!clear[index(a, b, c)] || reached[index(a, b, c)]) continue;
      reached[index(a, b, c)] = 1;
      queue.push_back({a, b, c});
    }
  }
  std::size_t mismatches = 0;
  std::size_t borderlines = 0;
  for (long k = 0; k < size[2]; ++k) {
    for (long j = 0; j < size[1]; ++j) {
      for (long i = 0; i < size[0]; ++i) {
        if (borderline[index(i, j, k)]) {
          ++borderlines;
          continue;
        }
        if (space.reachable(centre(i, j, k)) != bool(reached[index(i, j, k)])) ++mismatches;
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_LE(borderlines, 10u);
  EXPECT_NEAR(double(space.cell_count()), double(count), double(borderlines));
  EXPECT_GT(count, 10000u);  // the part holds a real piece of hall A
}

TEST(ReachableSpace, RejectsBadArguments) {
  const Scene scene = closed_room();
  EXPECT_THROW(ReachableSpace(scene, kRoom, 0.0, kRadius, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(ReachableSpace(scene, kRoom, kCell, -0.1, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(ReachableSpace(scene, {{2, 2, 2}, {0, 0, 0}}, kCell, kRadius, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(ReachableSpace(scene, kRoom, kCell, kRadius, {0.1, 1, 1}), std::invalid_argument);  // start too close
  EXPECT_THROW(ReachableSpace(scene, kRoom, kCell, kRadius, {3, 1, 1}), std::invalid_argument);    // outside
  EXPECT_THROW(ReachableSpace(scene, {{0, 0, 0}, {1e4, 1e4, 1e4}}, kCell, kRadius, {1, 1, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace umbra::sim
