// The projective integrator: its misses are exactly its per-voxel rule
// (projective_frame.hpp), evaluated brick by brick over the whole map by
// brute force, whatever nodes the tree walk decides whole; its hits are
// exactly the discrete integrator's on the image's points; the map does not
// depend on the thread count; and its maps agree with the simple
// integrator's (OctoMap's insertPointCloud) on simulated and real depth
// cameras within the fidelity thresholds of docs/benchmarks.md.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "integrate/projective_tracer.hpp"
#include "support/map_agreement.hpp"
#include "support/map_internals.hpp"
#include "support/test_support.hpp"
#include "tree/occupancy_tree.hpp"
#include "tree/update_batch.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

constexpr float kHit = 0.85f;
constexpr float kMiss = -0.4f;

/// Leaves of a tree as (code, depth, value) triples, for comparing trees.
std::vector<std::tuple<std::uint64_t, int, float>> leaves_of(const OccupancyTree& tree) {
  std::vector<std::tuple<std::uint64_t, int, float>> out;
  tree.for_each_leaf([&](NodeRef node, std::uint64_t code) { out.emplace_back(code, node.depth, tree.log_odds(node)); });
  return out;
}

OccupancyTree tree_from(const UpdateBatch& batch, int depth_levels) {
  OccupancyTree tree(depth_levels, LogOddsRange::from(SensorModel{}), LogOddsThresholds::from(Thresholds{}));
  tree.apply(batch, kHit, kMiss);
  return tree;
}

/// A random rigid pose: a random unit quaternion and a translation in [-t, t]^3.
Pose random_pose(std::mt19937& rng, double t) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-t, t);
  return Pose::from_translation_quaternion(u(rng), u(rng), u(rng), n(rng), n(rng), n(rng), n(rng));
}

/// A depth image of a bumpy surface at a random distance, with holes (no
/// reading), sometimes a few readings far beyond it, and noise.
std::vector<float> random_depths(std::mt19937& rng, int width, int height) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double far_share = u(rng) < 0.5 ? 0.0 : 0.02 * u(rng);
  const double base = 0.6 + 2.0 * u(rng);
  const double tilt_u = (u(rng) - 0.5) * 0.04;
  const double tilt_v = (u(rng) - 0.5) * 0.04;
  const double bump = 0.3 * u(rng);
  std::vector<float> depth(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    for (int px = 0; px < width; ++px) {
      double z = base + tilt_u * px + tilt_v * v + bump * std::sin(px * 0.3) * std::cos(v * 0.2);
      z += 0.01 * (u(rng) - 0.5);
      if (u(rng) < 0.03) z = 0.0;        // a single missing reading
      if (px > width / 2 && px < width / 2 + 6 && v > 5 && v < 20) z = 0.0;  // a hole
      if (u(rng) < far_share) z = 8.0;   // far behind
      depth[static_cast<std::size_t>(v) * width + px] = static_cast<float>(std::max(z, 0.0));
    }
  }
  return depth;
}

/// The rule's misses for the whole map, brick by brick (the definition).
UpdateBatch brute_force_misses(const ProjectiveRule& rule, int depth_levels) {
  UpdateBatch batch(depth_levels);
  const std::uint64_t voxels = std::uint64_t{1} << (3 * depth_levels);
  for (std::uint64_t brick = 0; brick < voxels; brick += 64) {
    std::uint64_t cleared = rule.cleared_plain(brick);
    if (rule.box_keys) {
      for (unsigned i = 0; i < 64; ++i) {
        if (!rule.box_keys->contains(morton::decode(brick + i))) cleared &= ~(std::uint64_t{1} << i);
      }
    }
    if (cleared != 0) batch.add_misses_in_brick(brick, cleared);
  }
  return batch;
}

TEST(ProjectiveIntegrator, TreeWalkClearsExactlyTheRulesVoxels) {
  std::mt19937 rng(7);
  constexpr int kDepthLevels = 7;  // 128^3 voxels: brute force over all of them
  int cases_with_misses = 0;
  for (int trial = 0; trial < 32; ++trial) {
    const Grid grid(trial % 3 == 0 ? 0.05 : 0.03, kDepthLevels);
    constexpr int kWidth = 48;
    constexpr int kHeight = 36;
    std::vector<float> depths = random_depths(rng, kWidth, kHeight);
    Pose pose = random_pose(rng, 0.8);
    if (trial % 8 == 4) {
      // A flat wall facing a camera that looks along the map's z axis, 2 mm
      // in front of the last layer of voxel centres of depth-3 nodes.
      pose = Pose::from_translation_quaternion(0.013, -0.021, 0.007, 1, 0, 0, 0);
      const double wall = (23 + 0.5) * grid.resolution() - 0.007 - 0.002;
      std::fill(depths.begin(), depths.end(), static_cast<float>(wall));
    }
    const DepthImage image = DepthImage::metres(depths, kWidth, kHeight);
    const PinholeCamera camera{40.0 + trial, 42.0, 23.5 + 0.3 * (trial % 4), 17.5};
    ProjectiveFrame frame;
    frame.set(image, camera, pose);
    const double max_range = trial % 4 == 1 || trial % 4 == 3 ? 1.7 : -1.0;
    const double margin = trial % 2 == 0 ? 0.0 : 0.5 * grid.resolution();
    std::optional<KeyBox> box;
    if (trial % 5 == 2) box = KeyBox{{40, 30, 50}, {90, 100, 77}};
    ProjectiveRule rule(grid, frame, max_range, margin, box);
    // A range this short applies voxel by voxel (range_depth 0); also try it
    // per node of 4 and 8 voxels, as longer ranges do.
    if (trial % 4 == 3) {
      ASSERT_EQ(rule.range_depth, 0);
      rule.range_depth = 2 + trial % 8 / 4;
      rule.max_range_squared = 0.0f;
    }
    const ProjectiveTracer tracer(rule);

    UpdateBatch walked(kDepthLevels);
    tracer.trace(0, kDepthLevels, walked);
    const UpdateBatch expected = brute_force_misses(rule, kDepthLevels);
    const auto walked_leaves = leaves_of(tree_from(walked, kDepthLevels));
    const auto expected_leaves = leaves_of(tree_from(expected, kDepthLevels));
    EXPECT_EQ(walked_leaves, expected_leaves) << "trial " << trial;
    cases_with_misses += expected_leaves.size() > 1 ? 1 : 0;
  }
  EXPECT_GE(cases_with_misses, 26);  // the scenes do clear something
}

TEST(ProjectiveIntegrator, AvxEqualsPlain) {
  // Every brick of the random scenes, the plain rule against the fast one.
  // Where the CPU has no AVX2 both are the plain one and this proves nothing.
  std::mt19937 rng(5);
  constexpr int kDepthLevels = 6;
  std::size_t cleared_bricks = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Grid grid(0.02 + 0.01 * (trial % 3), kDepthLevels);
    const std::vector<float> depths = random_depths(rng, 64, 48);
    ProjectiveFrame frame;
    frame.set(DepthImage::metres(depths, 64, 48), PinholeCamera{30.0 + 20 * trial, 45.0, 31.5, 23.5},
              random_pose(rng, 0.3));
    const ProjectiveRule rule(grid, frame, trial % 2 == 0 ? 0.9 : -1.0, 0.01 * (trial % 3), std::nullopt);
    for (std::uint64_t brick = 0; brick < (std::uint64_t{1} << (3 * kDepthLevels)); brick += 64) {
      const std::uint64_t plain = rule.cleared_plain(brick);
      ASSERT_EQ(rule.cleared(brick), plain) << "trial " << trial << " brick " << brick;
      cleared_bricks += plain != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(cleared_bricks, 1000u);
}

TEST(ProjectiveIntegrator, WholeNodesAreDecided) {
  // A wall 2 m in front of a camera: the free space in front of it must be
  // cleared mostly by whole nodes, not brick by brick.
  const Grid grid(0.02, 10);
  constexpr int kWidth = 64;
  constexpr int kHeight = 48;
  const std::vector<float> depths(kWidth * kHeight, 2.01f);
  ProjectiveFrame frame;
  frame.set(DepthImage::metres(depths, kWidth, kHeight), PinholeCamera{50, 50, 31.5, 23.5},
            Pose::from_translation_quaternion(0.011, 0.003, 0.007, 1, 0, 0, 0));
  const ProjectiveRule rule(grid, frame, -1.0, 0.0, std::nullopt);
  const ProjectiveTracer tracer(rule);
  UpdateBatch batch(10);
  tracer.trace(0, 10, batch);
  const OccupancyTree tree = tree_from(batch, 10);
  std::uint64_t cleared = 0;
  for (const auto& [code, depth, value] : leaves_of(tree)) {
    if (value < 0.0f) cleared += std::uint64_t{1} << (3 * depth);
  }
  // The pyramid in front of the wall holds about 410,000 voxels; the
  // batch marks it with far fewer groups.
  EXPECT_GT(cleared, 350000u);
  std::size_t groups = batch.group_count(1);
  for (int d = 2; d < 10; ++d) groups += batch.group_count(d);
  EXPECT_LT(groups, cleared / 50);
}

/// Occupied voxels of a map, as sorted codes.
std::vector<std::uint64_t> occupied_codes(const OccupancyMap& map) {
  std::vector<std::uint64_t> codes;
  map.for_each_leaf([&](const Node& node) {
    if (node.state != OccupancyState::occupied) return;
    const std::uint64_t first = node.code();
    for (std::uint64_t i = 0; i < (std::uint64_t{1} << (3 * node.depth)); ++i) codes.push_back(first + i);
  });
  std::sort(codes.begin(), codes.end());
  return codes;
}

TEST(ProjectiveIntegrator, HitsAreTheDiscreteIntegrators) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    constexpr int kWidth = 40;
    constexpr int kHeight = 30;
    const std::vector<float> depths = random_depths(rng, kWidth, kHeight);
    const DepthImage image = DepthImage::metres(depths, kWidth, kHeight);
    const PinholeCamera camera{35.0, 35.0, 19.5, 14.5};
    const Pose pose = random_pose(rng, 0.5);
    InsertOptions options;
    options.max_range = trial % 2 == 0 ? 2.2 : -1.0;
    options.threads = 1;

    OccupancyMap projective(0.04, 9);
    OccupancyMap discrete(0.04, 9);
    if (trial % 3 == 1) {
      const Aabb box{{-1.0, -1.5, -2.0}, {2.0, 1.0, 1.5}};
      projective.set_bounding_box(box);
      discrete.set_bounding_box(box);
    }
    options.integrator = IntegratorKind::projective;
    const InsertStats p = projective.insert_depth_image(image, camera, pose, {}, options);
    options.integrator = IntegratorKind::discrete;
    std::vector<Vec3f> points;
    back_project(image, camera, pose, points);
    const InsertStats d = discrete.insert_point_cloud(pose.translation(), points, options);
    EXPECT_EQ(occupied_codes(projective), occupied_codes(discrete)) << "trial " << trial;
    EXPECT_EQ(p.hits, d.hits) << "trial " << trial;
    EXPECT_EQ(p.truncated, d.truncated) << "trial " << trial;
    EXPECT_TRUE(test::check_invariants(projective).empty());
  }
}

TEST(ProjectiveIntegrator, SameMapForAnyThreadCount) {
  const std::vector<sim::SimulatedDepthImage> frames = sim::demo_depth_images(3);
  for (const double res : {0.05, 0.02}) {
    std::vector<std::vector<std::tuple<std::uint64_t, int, float>>> results;
    for (const unsigned threads : {1u, 2u, 3u, 8u, 16u}) {
      OccupancyMap map(res);
      InsertOptions options;
      options.integrator = IntegratorKind::projective;
      options.max_range = 6.0;
      options.threads = threads;
      for (std::size_t i = 0; i < 6; ++i) map.insert_depth_image(frames[i].view(), frames[i].camera, frames[i].pose, {}, options);
      ASSERT_TRUE(test::check_invariants(map).empty());
      results.push_back(leaves_of(test::tree_of(map)));
    }
    for (std::size_t i = 1; i < results.size(); ++i) EXPECT_EQ(results[i], results[0]) << "res " << res << " run " << i;
  }
}

/// The simple integrator's map and the projective one's of the same frames.
test::MapAgreement agreement(const std::vector<sim::SimulatedDepthImage>& frames, std::size_t count, double res,
                             double max_range) {
  OccupancyMap simple(res);
  OccupancyMap projective(res);
  InsertOptions options;
  options.max_range = max_range;
  std::vector<Vec3f> points;
  for (std::size_t i = 0; i < count; ++i) {
    const sim::SimulatedDepthImage& f = frames[i];
    back_project(f.view(), f.camera, f.pose, points);
    options.integrator = IntegratorKind::simple;
    simple.insert_point_cloud(f.pose.translation(), points, options);
    options.integrator = IntegratorKind::projective;
    projective.insert_depth_image(f.view(), f.camera, f.pose, {}, options);
  }
  return test::compare_maps(simple, projective);
}

TEST(ProjectiveIntegrator, AgreesWithSimpleOnTheSimulatedCamera) {
  const std::vector<sim::SimulatedDepthImage> frames = sim::demo_depth_images(1);
  const test::MapAgreement a = agreement(frames, 8, 0.04, 6.5);
  std::printf("simulated camera, 8 frames, 4 cm: recall %.4f precision %.4f free left unknown %.4f\n", a.recall(),
              a.precision(), a.free_left_unknown());
  EXPECT_GE(a.recall(), 0.995);
  EXPECT_GE(a.precision(), 0.99);
  EXPECT_LE(a.free_left_unknown(), 0.05);
}

}  // namespace
}  // namespace umbra
