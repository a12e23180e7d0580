// Bounding box: rays are clipped to the box, never dropped, and only voxels
// in the box change. Checked ray by ray against a brute-force reference: the
// voxels in the box whose cube the (clipped) segment passes through.
#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "support/map_internals.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

/// Length of the part of segment a-b inside the cube [low, low + size]^3.
double length_inside(Vec3d a, Vec3d b, Vec3d low, double size) {
  const Aabb cube{low, low + Vec3d{size, size, size}};
  const auto part = cube.clip(a, b);
  return part ? (part->second - part->first) * (b - a).norm() : -1.0;
}

TEST(BoundingBox, OnlyVoxelsTheClippedRayCrossesInsideTheBoxChange) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> anywhere(-6.0f, 6.0f);
  std::uniform_real_distribution<double> corner(-3.0, 3.0);
  std::size_t rays_with_end_outside = 0;
  std::size_t checked = 0;
  for (const IntegratorKind kind : {IntegratorKind::simple, IntegratorKind::fast}) {
    for (int trial = 0; trial < 60; ++trial) {
      OccupancyMap map(0.1, 7);  // [-6.4, 6.4)
      const Vec3d low{corner(rng), corner(rng), corner(rng)};
      const Vec3d high =
          low + Vec3d{1.0 + 0.5 * std::abs(corner(rng)), 1.0 + 0.5 * std::abs(corner(rng)), 1.0 + 0.5 * std::abs(corner(rng))};
      const Aabb box{low, high};
      map.set_bounding_box(box);
      // Aim through a point of the box, ending before, in or beyond it.
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      const Vec3d aim = low + Vec3d{(high.x - low.x) * unit(rng), (high.y - low.y) * unit(rng), (high.z - low.z) * unit(rng)};
      const Vec3f origin{anywhere(rng), anywhere(rng), anywhere(rng)};
      Vec3d far = Vec3d(origin) + (aim - Vec3d(origin)) * (0.6 + 1.2 * unit(rng));
      for (int axis = 0; axis < 3; ++axis) far[axis] = std::clamp(far[axis], -6.3, 6.3);
      const auto end = static_cast<Vec3f>(far);
      InsertOptions options;
      options.integrator = kind;
      options.fine_steps = 0;
      options.clear_depth = 1;
      const InsertStats stats = map.insert_point_cloud(origin, std::vector<Vec3f>{end}, options);
      const Vec3d target(end);  // the fast integrator aims at the first point of the end voxel: this one
      const auto part = box.clip(Vec3d(origin), target);
      if (!part) {
        EXPECT_EQ(stats.outside_box, 1u);
        EXPECT_EQ(map.node_counts().total(), 1u) << "a ray that misses the box changes nothing";
        continue;
      }
      const Vec3d d = target - Vec3d(origin);
      const Vec3d a = Vec3d(origin) + d * part->first;
      const Vec3d b = Vec3d(origin) + d * part->second;
      const bool end_inside = part->second == 1.0;
      rays_with_end_outside += !end_inside;
      const Key end_key = map.key(target);
      const Key box_low = map.key(box.min);
      const Key box_high = map.key(box.max);
      const std::uint32_t size = map.grid().keys_per_axis();
      for (std::uint32_t z = 0; z < size; ++z) {
        for (std::uint32_t y = 0; y < size; ++y) {
          for (std::uint32_t x = 0; x < size; ++x) {
            const Key key{x, y, z};
            const OccupancyState state = test::log_odds_thresholds(map).classify(map.node(key).log_odds);
            const bool in_box = x >= box_low.x && x <= box_high.x && y >= box_low.y && y <= box_high.y &&
                                z >= box_low.z && z <= box_high.z;
            if (!in_box) {
              ASSERT_EQ(state, OccupancyState::unknown) << "voxel outside the box changed, trial " << trial;
              continue;
            }
            if (key == end_key && end_inside) {
              ASSERT_EQ(state, OccupancyState::occupied) << "trial " << trial;
              continue;
            }
            const double inside = length_inside(a, b, map.grid().min_corner(key), map.resolution());
            if (kind == IntegratorKind::simple) {
              if (inside > 1e-4) {
                ASSERT_EQ(state, OccupancyState::free) << "crossed voxel not cleared, trial " << trial;
                ++checked;
              } else if (inside < 0) {
                ASSERT_EQ(state, OccupancyState::unknown) << "voxel off the ray changed, trial " << trial;
              }
            } else if (inside > 1e-4 && key.at_depth(1) != map.key(b).at_depth(1)) {
              // Coarse clearing may free whole nodes around the ray, never leave a crossed voxel unknown
              // (the end node is traced voxel by voxel, and checked like the rest but for its end).
              ASSERT_EQ(state, OccupancyState::free) << "crossed voxel not cleared (fast), trial " << trial;
              ++checked;
            }
          }
        }
      }
    }
  }
  EXPECT_GT(rays_with_end_outside, 10u) << "points outside the box must be tested too";
  EXPECT_GT(checked, 500u);
}

TEST(BoundingBox, BadBoxesAreRejected) {
  OccupancyMap map(0.1);
  EXPECT_THROW(map.set_bounding_box(Aabb{{0, 0, 0}, {-1, 1, 1}}), std::invalid_argument);
  EXPECT_THROW(map.set_bounding_box(Aabb{{0, 0, std::nan("")}, {1, 1, 1}}), std::invalid_argument);
  map.set_bounding_box(Aabb{{0, 0, 0}, {1, 1, 1}});
  EXPECT_TRUE(map.bounding_box().has_value());
  map.set_bounding_box(std::nullopt);
  EXPECT_FALSE(map.bounding_box().has_value());
}

}  // namespace
}  // namespace umbra
