// Tests of the procedural plant: deterministic from its seed, the building
// the header describes (size, levels, openings between them), a free start,
// and for several seeds free space that a 0.3 m robot reaches on every level
// of every hall from the start.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "umbra/sim/industrial_scene.hpp"
#include "umbra/sim/reachable_space.hpp"

namespace umbra::sim {
namespace {

bool same_primitives(const Scene& a, const Scene& b) {
  if (a.boxes().size() != b.boxes().size() || a.cylinders().size() != b.cylinders().size() ||
      a.pipes().size() != b.pipes().size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.boxes().size(); ++i) {
    if (a.boxes()[i].min != b.boxes()[i].min || a.boxes()[i].max != b.boxes()[i].max) return false;
  }
  for (std::size_t i = 0; i < a.cylinders().size(); ++i) {
    const Cylinder& p = a.cylinders()[i];
    const Cylinder& q = b.cylinders()[i];
    if (p.center_x != q.center_x || p.center_y != q.center_y || p.radius != q.radius || p.z_min != q.z_min ||
        p.z_max != q.z_max) {
      return false;
    }
  }
  for (std::size_t i = 0; i < a.pipes().size(); ++i) {
    const Pipe& p = a.pipes()[i];
    const Pipe& q = b.pipes()[i];
    if (p.a != q.a || p.b != q.b || p.radius != q.radius) return false;
  }
  return true;
}

TEST(IndustrialScene, SameSeedSameSceneOtherSeedOtherScene) {
  const IndustrialPlant one = make_industrial_scene(1);
  EXPECT_TRUE(same_primitives(one.scene, make_industrial_scene(1).scene));
  EXPECT_FALSE(same_primitives(one.scene, make_industrial_scene(2).scene));
}

TEST(IndustrialScene, IsTheDescribedBuilding) {
  const IndustrialPlant plant = make_industrial_scene(1);
  const Scene& scene = plant.scene;
  const Box bounds = scene.bounds();
  EXPECT_EQ(bounds.min, (Vec3d{0, 0, -0.3}));
  EXPECT_EQ(bounds.max, (Vec3d{40, 30, 12.3}));
  EXPECT_EQ(plant.interior.min, (Vec3d{0.3, 0.3, 0.0}));
  EXPECT_EQ(plant.interior.max, (Vec3d{39.7, 29.7, 12.0}));
  EXPECT_GE(scene.primitive_count(), 600u);
  EXPECT_GE(scene.cylinders().size(), 10u);  // tanks, columns, pumps
  EXPECT_GE(scene.pipes().size(), 100u);

  EXPECT_FALSE(scene.is_inside_solid(plant.start));
  EXPECT_GE(scene.distance_to_nearest_surface(plant.start), 1.5);

  // Hall B's floor at 5.8..6 m, with a hatch x in [22, 25.5], y in [6, 9.5]
  // through which the roof (z = 12) is seen from the ground.
  const auto up_beside_hatch = scene.intersect({21.5, 7.75, 1.0}, {0, 0, 1}, 20.0);
  ASSERT_TRUE(up_beside_hatch.has_value());
  EXPECT_NEAR(*up_beside_hatch, 4.8, 1e-9);
  const auto up_through_hatch = scene.intersect({23.75, 7.75, 1.0}, {0, 0, 1}, 20.0);
  ASSERT_TRUE(up_through_hatch.has_value());
  EXPECT_NEAR(*up_through_hatch, 11.0, 1e-9);
  // Hall A is full height north of its mezzanine, which ends at y = 10.
  const auto up_in_hall_a = scene.intersect(plant.start, {0, 0, 1}, 20.0);
  ASSERT_TRUE(up_in_hall_a.has_value());
  EXPECT_GT(*up_in_hall_a, 9.0);
  const auto up_under_mezzanine = scene.intersect({7.0, 9.0, 1.5}, {0, 0, 1}, 20.0);
  ASSERT_TRUE(up_under_mezzanine.has_value());
  EXPECT_LE(*up_under_mezzanine, 4.3 + 1e-9);
  // The ground door from hall A to hall B (y in [12, 14.5], 3.5 m high) is open.
  const auto through_door = scene.intersect({11.0, 13.25, 1.5}, {1, 0, 0}, 20.0);
  ASSERT_TRUE(through_door.has_value());
  EXPECT_GT(*through_door, 5.0);
}

TEST(IndustrialScene, EveryHallAndLevelIsReachableForSeveralSeeds) {
  // Points in the zones the generator keeps free: the start, the doors on
  // both levels (both sides), the mezzanine landing, hall B's upper floor by
  // its hatch, hall C's gallery.
  const Vec3d kept_free[] = {
      {7.0, 15.0, 1.5},    // start, hall A ground
      {12.5, 13.25, 1.5},  // hall A at the door to B
      {15.8, 13.25, 1.5},  // hall B ground at the same door
      {12.5, 4.25, 7.2},   // hall A mezzanine at the upper door to B
      {15.8, 4.25, 7.2},   // hall B upper floor at the same door
      {23.75, 7.75, 3.0},  // hall B ground under the hatch
      {23.75, 7.75, 9.0},  // hall B upper floor over the hatch
      {25.25, 17.5, 1.5},  // hall C ground at the door from B
      {32.25, 17.5, 7.2},  // hall C gallery at the upper door from B
      {15.8, 22.75, 2.0},  // hall C at the gate from A
      {1.5, 15.0, 6.5},    // over hall A's stair
  };
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const IndustrialPlant plant = make_industrial_scene(seed);
    const ReachableSpace space(plant.scene, plant.interior, 0.16, 0.3, plant.start);
    for (const Vec3d& p : kept_free) {
      EXPECT_TRUE(space.reachable(p)) << p.x << ", " << p.y << ", " << p.z;
    }
    // Nearly all clear space is joined; it fills most of the building.
    EXPECT_GE(double(space.cell_count()), 0.99 * double(space.clear_cell_count()));
    const Vec3d size = plant.interior.max - plant.interior.min;
    EXPECT_GT(space.volume(), 0.6 * size.x * size.y * size.z);
  }
}

}  // namespace
}  // namespace umbra::sim
