// Tests of the reachable-space ground truth on rooms small enough to count
// by hand: a closed 2 m cube, the cube split by a wall, the wall with a
// window; counts of boxes of cells; bad arguments.
#include <gtest/gtest.h>

#include <stdexcept>

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
