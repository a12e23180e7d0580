// Tests of the scene's pipes and of its bounding volume hierarchy: pipe
// geometry against hand-computed values and a fine ray march; every query of
// a scene of thousands of random primitives against brute force (the
// nearest answer over one-primitive scenes, whose hierarchy is a single
// leaf); the hierarchy's height whatever the order of insertion; copies and
// moves.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "scene_bvh.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {
namespace {

Vec3d unit(Vec3d v) { return v / v.norm(); }

Scene one_pipe(const Pipe& pipe) {
  Scene scene;
  scene.add_pipe(pipe);
  return scene;
}

// --- pipes -----------------------------------------------------------------

TEST(ScenePipe, RaysAgainstAHorizontalPipeByHand) {
  const Scene scene = one_pipe({{0, 0, 0}, {4, 0, 0}, 1.0});
  auto hit = scene.intersect({2, -5, 0}, {0, 1, 0}, 100.0);  // across the tube
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  hit = scene.intersect({2, 0, 5}, {0, 0, -1}, 100.0);  // from above
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  hit = scene.intersect({-5, 0, 0}, {1, 0, 0}, 100.0);  // along the axis: the rounded end at x = -1
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  hit = scene.intersect({6, 0, 0.5}, {-1, 0, 0}, 100.0);  // into the far end ball off the axis
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 2.0 - std::sqrt(0.75), 1e-12);
  EXPECT_FALSE(scene.intersect({0, 1.01, 0}, {1, 0, 0}, 100.0).has_value());  // parallel, outside
  EXPECT_FALSE(scene.intersect({-2, -5, 0}, {0, 1, 0}, 100.0).has_value());   // beyond the end ball
  hit = scene.intersect({2, 0.5, 0}, {0, 0, 1}, 100.0);  // starting inside
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(*hit, 0.0);
}

TEST(ScenePipe, InsideDistanceAndBounds) {
  const Pipe pipe{{0, 0, 0}, {0, 3, 4}, 0.5};  // length 5, slanted
  const Scene scene = one_pipe(pipe);
  EXPECT_TRUE(scene.is_inside_solid({0, 1.5, 2.0}));
  EXPECT_TRUE(scene.is_inside_solid({0, -0.3, -0.3}));  // in the end ball (0.42 from a)
  EXPECT_FALSE(scene.is_inside_solid({0, -0.4, -0.4}));  // 0.57 from a
  // From (0, 4 + 1.5, 3 - 2): 2.5 m across the axis, 2 m from the surface.
  const Vec3d across{0.0, 1.5 + 4.0 * 0.5, 2.0 - 3.0 * 0.5};
  EXPECT_NEAR(scene.distance_to_nearest_surface(across), 2.0, 1e-12);
  EXPECT_NEAR(distance_to_solid(pipe, across), 2.0, 1e-12);
  EXPECT_EQ(distance_to_solid(pipe, {0, 1.5, 2.0}), 0.0);
  EXPECT_NEAR(scene.distance_to_nearest_surface({0, 1.5, 2.0}), 0.5, 1e-12);  // on the axis
  EXPECT_NEAR(scene.distance_to_nearest_surface({0, 3, 7}), 2.5, 1e-12);     // past b, on the axis line
  const Box bounds = scene.bounds();
  EXPECT_EQ(bounds.min, (Vec3d{-0.5, -0.5, -0.5}));
  EXPECT_EQ(bounds.max, (Vec3d{0.5, 3.5, 4.5}));
  // A ball: both ends the same.
  const Scene ball = one_pipe({{1, 1, 1}, {1, 1, 1}, 1.0});
  const auto hit = ball.intersect({1, 1, -4}, {0, 0, 1}, 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
}

TEST(ScenePipe, RayHitsAgreeWithAFineMarchAlongTheRay) {
  // The first point along the ray whose distance to the segment is at most
  // the radius, found by marching in 1 mm steps and bisecting the last one:
  // the analytic hit must agree.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  int hits = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Pipe pipe{{coordinate(rng), coordinate(rng), coordinate(rng)},
                    {coordinate(rng), coordinate(rng), coordinate(rng)},
                    0.2 + 0.5 * std::abs(coordinate(rng)) / 3.0};
    const Scene scene = one_pipe(pipe);
    Vec3d origin{coordinate(rng) * 2, coordinate(rng) * 2, coordinate(rng) * 2};
    if (scene.is_inside_solid(origin)) continue;
    // Aim near the pipe's middle so that about half the rays hit.
    const Vec3d target = (pipe.a + pipe.b) * 0.5 + Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)} * 0.4;
    const Vec3d direction = unit(target - origin);
    const auto hit = scene.intersect(origin, direction, 20.0);
    std::optional<double> marched;
    constexpr double step = 1e-3;
    for (double t = 0.0; t <= 20.0; t += step) {
      if (distance_to_solid(pipe, origin + direction * t) == 0.0) {
        // Bisect between the last point outside and this one.
        double outside = t - step;
        double inside = t;
        for (int i = 0; i < 40; ++i) {
          const double middle = 0.5 * (outside + inside);
          (distance_to_solid(pipe, origin + direction * middle) == 0.0 ? inside : outside) = middle;
        }
        marched = inside;
        break;
      }
    }
    ASSERT_EQ(hit.has_value(), marched.has_value()) << "trial " << trial;
    if (hit) {
      ++hits;
      EXPECT_NEAR(*hit, *marched, 1e-9) << "trial " << trial;
    }
  }
  EXPECT_GT(hits, 60);
}

TEST(ScenePipe, RejectsBadPipes) {
  Scene scene;
  EXPECT_THROW(scene.add_pipe({{0, 0, 0}, {1, 0, 0}, 0.0}), std::invalid_argument);
  EXPECT_THROW(scene.add_pipe({{0, 0, 0}, {1, 0, 0}, -1.0}), std::invalid_argument);
  EXPECT_THROW(scene.add_pipe({{0, 0, NAN}, {1, 0, 0}, 1.0}), std::invalid_argument);
  EXPECT_THROW(scene.add_pipe({{0, 0, 0}, {1, 0, 0}, INFINITY}), std::invalid_argument);
  EXPECT_TRUE(scene.empty());
}

// --- the hierarchy against brute force --------------------------------------

/// A scene of `count` random boxes, cylinders and pipes of mixed sizes in a
/// 40 x 30 x 12 m space, and the same primitives as one-primitive scenes.
struct RandomWorld {
  Scene scene;
  std::vector<Scene> singles;
};

RandomWorld random_world(int count, std::uint32_t seed) {
  RandomWorld world;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(0.0, 40.0);
  std::uniform_real_distribution<double> y(0.0, 30.0);
  std::uniform_real_distribution<double> z(0.0, 12.0);
  std::uniform_real_distribution<double> size(0.05, 1.5);
  std::uniform_int_distribution<int> kind(0, 9);
  for (int i = 0; i < count; ++i) {
    Scene single;
    const int k = kind(rng);
    if (k == 0) {  // now and then a large slab, as floors and walls are
      const Vec3d a{x(rng), y(rng), z(rng)};
      const int thin = i % 3;
      Vec3d b = a + Vec3d{10.0, 8.0, 5.0};
      b[std::size_t(thin)] = a[std::size_t(thin)] + 0.2;
      single.add_box({a, b});
    } else if (k <= 4) {
      const Vec3d a{x(rng), y(rng), z(rng)};
      single.add_box({a, a + Vec3d{size(rng), size(rng), size(rng)}});
    } else if (k <= 6) {
      const double z0 = z(rng);
      single.add_cylinder({x(rng), y(rng), size(rng), z0, z0 + 3 * size(rng)});
    } else {
      const Vec3d a{x(rng), y(rng), z(rng)};
      single.add_pipe({a, a + Vec3d{4 * size(rng) - 3, 4 * size(rng) - 3, 2 * size(rng) - 1.5}, 0.1 * size(rng)});
    }
    for (const Box& b : single.boxes()) world.scene.add_box(b);
    for (const Cylinder& c : single.cylinders()) world.scene.add_cylinder(c);
    for (const Pipe& p : single.pipes()) world.scene.add_pipe(p);
    world.singles.push_back(std::move(single));
  }
  return world;
}

TEST(SceneHierarchy, RayCastsAgreeWithBruteForce) {
  const RandomWorld world = random_world(3000, 5);
  ASSERT_EQ(world.scene.primitive_count(), 3000u);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> x(-5.0, 45.0);
  std::uniform_real_distribution<double> y(-5.0, 35.0);
  std::uniform_real_distribution<double> z(-2.0, 14.0);
  std::normal_distribution<double> gaussian;
  int hits = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Vec3d origin{x(rng), y(rng), z(rng)};
    Vec3d direction{gaussian(rng), gaussian(rng), gaussian(rng)};
    // Some rays along the axes, the degenerate case of the slab tests.
    if (trial % 10 == 0) direction = {trial % 20 == 0 ? 1.0 : 0.0, 0.0, trial % 20 == 0 ? 0.0 : -1.0};
    direction = unit(direction);
    const double range = trial % 2 == 0 ? std::numeric_limits<double>::infinity() : 8.0;
    std::optional<double> expected;
    for (const Scene& single : world.singles) {
      const auto hit = single.intersect(origin, direction, range);
      if (hit && (!expected || *hit < *expected)) expected = hit;
    }
    const auto hit = world.scene.intersect(origin, direction, range);
    ASSERT_EQ(hit.has_value(), expected.has_value()) << "trial " << trial;
    if (hit) {
      ++hits;
      EXPECT_EQ(*hit, *expected) << "trial " << trial;
    }
  }
  EXPECT_GT(hits, 1000);
}

TEST(SceneHierarchy, InsideAndDistanceAgreeWithBruteForce) {
  const RandomWorld world = random_world(2000, 7);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> x(-5.0, 45.0);
  std::uniform_real_distribution<double> y(-5.0, 35.0);
  std::uniform_real_distribution<double> z(-2.0, 14.0);
  int inside = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Vec3d point{x(rng), y(rng), z(rng)};
    bool expected_inside = false;
    double expected_distance = std::numeric_limits<double>::infinity();
    for (const Scene& single : world.singles) {
      expected_inside = expected_inside || single.is_inside_solid(point);
      expected_distance = std::min(expected_distance, single.distance_to_nearest_surface(point));
    }
    ASSERT_EQ(world.scene.is_inside_solid(point), expected_inside) << "trial " << trial;
    ASSERT_EQ(world.scene.distance_to_nearest_surface(point), expected_distance) << "trial " << trial;
    inside += expected_inside ? 1 : 0;
  }
  EXPECT_GT(inside, 50);
}

TEST(SceneHierarchy, StaysShallowWhateverTheOrderOfInsertion) {
  // Sorted along x (the worst case for a tree that only appends), shuffled,
  // and all stacked at one spot: an AVL tree of n leaves is at most
  // 1.44 log2(n) + 2 high; the surface-area descent may leave it a little higher.
  constexpr int n = 4096;
  std::vector<detail::BvhBox> boxes;
  for (int i = 0; i < n; ++i) boxes.push_back({{double(i), 0, 0}, {double(i) + 0.5, 1, 1}});
  std::vector<detail::BvhBox> shuffled = boxes;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(3));
  std::vector<detail::BvhBox> stacked(n, detail::BvhBox{{0, 0, 0}, {1, 1, 1}});
  for (const auto* order : {&boxes, &shuffled, &stacked}) {
    detail::SceneBvh bvh;
    for (std::size_t i = 0; i < order->size(); ++i) bvh.insert((*order)[i], std::uint32_t(i));
    EXPECT_LE(bvh.height(), int(2.0 * std::log2(double(n))) + 2);
    EXPECT_GE(bvh.height(), int(std::log2(double(n))));
  }
}

TEST(SceneHierarchy, CopiesAreIndependentAndMovedFromScenesAreEmpty) {
  Scene original;
  original.add_box({{1, -1, -1}, {2, 1, 1}});
  Scene copy = original;
  copy.add_pipe({{0.5, -1, 0}, {0.5, 1, 0}, 0.1});
  EXPECT_NEAR(*original.intersect({0, 0, 0}, {1, 0, 0}, 10.0), 1.0, 1e-12);
  EXPECT_NEAR(*copy.intersect({0, 0, 0}, {1, 0, 0}, 10.0), 0.4, 1e-12);

  Scene moved = std::move(copy);
  EXPECT_EQ(moved.primitive_count(), 2u);
  EXPECT_NEAR(*moved.intersect({0, 0, 0}, {1, 0, 0}, 10.0), 0.4, 1e-12);
  EXPECT_TRUE(copy.empty());  // NOLINT(bugprone-use-after-move): documented state
  EXPECT_FALSE(copy.intersect({0, 0, 0}, {1, 0, 0}, 10.0).has_value());
  copy.add_box({{3, -1, -1}, {4, 1, 1}});
  EXPECT_NEAR(*copy.intersect({0, 0, 0}, {1, 0, 0}, 10.0), 3.0, 1e-12);

  Scene assigned;
  assigned = original;
  assigned = std::move(moved);
  EXPECT_EQ(assigned.primitive_count(), 2u);
  EXPECT_NEAR(*assigned.intersect({0, 0, 0}, {1, 0, 0}, 10.0), 0.4, 1e-12);
}

}  // namespace
}  // namespace umbra::sim
