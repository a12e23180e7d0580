// Tests of the clearance checks from a distance field
// (examples/explore/field_clearance.hpp): on an umbra map of the plant seen
// from the start, frame by frame, the field's answer for random balls and
// capsules (random centres, radii and lengths around the robot, the planner's
// radius among them) equals the map's own is_free() after every frame, and
// the field decided most of them itself (else the test would only test the
// fallback). Then the planner on a map with the field and on one with the
// map's checks, fed the same frames, grows the same trees and takes the same
// steps.
#include <gtest/gtest.h>

#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "field_clearance.hpp"
#include "nbv_planner.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/industrial_scene.hpp"
#include "umbra_exploration_map.hpp"

namespace umbra::explore {
namespace {

sim::DepthCameraModel small_camera() {
  sim::DepthCameraModel camera;
  camera.width = 96;
  camera.height = 50;
  camera.emit_no_return = true;
  camera.no_return_range = camera.max_range + 1.0;
  return camera;
}

/// Uniform in [low, high) from the engine's bits, the same with every standard library.
double uniform(std::mt19937& rng, double low, double high) {
  return low + (high - low) * (double(rng()) / 4294967296.0);
}

TEST(FieldClearance, BallsAndCapsulesAnswerAsTheMapsChecksAfterEveryFrame) {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  UmbraMapOptions options;
  options.clearance = ClearanceSource::distance_field;
  UmbraExplorationMap map(options);
  ASSERT_NE(map.field_clearance(), nullptr);
  const FieldClearance& clearance = *map.field_clearance();
  map.assume_free(Sphere{plant.start, 1.0});

  const sim::DepthCameraModel camera = small_camera();
  std::vector<Vec3f> points;
  std::mt19937 rng(7);
  int free_balls = 0, blocked_balls = 0, free_capsules = 0, blocked_capsules = 0;
  for (int frame = 0; frame < 6; ++frame) {
    const double yaw = 2.0 * std::numbers::pi * frame / 6.0;
    sim::simulate_depth_image(plant.scene, {plant.start, yaw, 0.0}, camera, points);
    map.insert(Vec3f(plant.start), points, camera.max_range);
    for (int i = 0; i < 400; ++i) {
      SCOPED_TRACE("frame " + std::to_string(frame) + ", check " + std::to_string(i));
      const Vec3d p = plant.start + Vec3d{uniform(rng, -5.0, 5.0), uniform(rng, -5.0, 5.0), uniform(rng, -1.5, 1.5)};
      // Every third check has the planner's radius, the rest any from 0 to beyond the field's reach.
      const double r = i % 3 == 0 ? PlannerConfig{}.check_radius() : uniform(rng, 0.0, 1.2);
      const Sphere ball{p, r};
      const bool expected_ball = map.map().is_free(ball).free;
      EXPECT_EQ(clearance.is_free(ball), expected_ball) << "ball at " << p.x << " " << p.y << " " << p.z << " r " << r;
      (expected_ball ? free_balls : blocked_balls)++;

      const Vec3d direction{uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0), uniform(rng, -0.5, 0.5)};
      const double length = i % 10 == 0 ? 0.0 : uniform(rng, 0.0, 3.0);
      const Capsule path{p, p + direction * (length / std::max(1e-9, direction.norm())), r};
      const bool expected_path = map.map().is_free(path).free;
      EXPECT_EQ(clearance.is_free(path), expected_path) << "capsule from " << p.x << " " << p.y << " " << p.z
                                                        << " length " << length << " r " << r;
      (expected_path ? free_capsules : blocked_capsules)++;
    }
  }
  // Both answers came up often, and the field (not the fallback) gave most.
  EXPECT_GE(free_balls, 300);
  EXPECT_GE(blocked_balls, 300);
  EXPECT_GE(free_capsules, 150);
  EXPECT_GE(blocked_capsules, 300);
  const ClearanceCounts counts = clearance.counts();
  EXPECT_GE(counts.balls_by_field, 3u * counts.balls_by_map);
  EXPECT_GE(counts.capsules_by_field, 2u * counts.capsules_by_map);
}

TEST(FieldClearance, ThePlannerTakesTheSameStepsWithTheFieldAsWithTheMapsChecks) {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  UmbraMapOptions with_field;
  with_field.clearance = ClearanceSource::distance_field;
  UmbraExplorationMap field_map(with_field);
  UmbraExplorationMap checks_map(UmbraMapOptions{});
  for (UmbraExplorationMap* map : {&field_map, &checks_map}) map->assume_free(Sphere{plant.start, 1.0});

  PlannerConfig config;
  config.bounds = Aabb{plant.interior.min, plant.interior.max};
  config.initial_nodes = 30;
  config.max_nodes = 30;
  config.max_nodes_no_gain = 60;
  NbvPlanner field_planner(config, 3);
  NbvPlanner checks_planner(config, 3);
  const sim::DepthCameraModel camera = small_camera();
  std::vector<Vec3f> points;
  Pose robot{plant.start, 0.0};
  std::size_t nodes_compared = 0;
  for (int step = 0; step < 6; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    // The robot looks around where it is, then both planners plan from there.
    for (int k = 0; k < 3; ++k) {
      sim::simulate_depth_image(plant.scene, {robot.position, robot.yaw + 2.0 * k, 0.0}, camera, points);
      for (UmbraExplorationMap* map : {&field_map, &checks_map}) map->insert(Vec3f(robot.position), points, camera.max_range);
    }
    const PlanStep a = field_planner.plan(field_map, robot);
    const PlanStep b = checks_planner.plan(checks_map, robot);
    ASSERT_EQ(field_planner.tree().size(), checks_planner.tree().size());
    for (std::size_t i = 0; i < field_planner.tree().size(); ++i) {
      EXPECT_EQ(field_planner.tree()[i].pose.position, checks_planner.tree()[i].pose.position) << "node " << i;
      EXPECT_EQ(field_planner.tree()[i].parent, checks_planner.tree()[i].parent) << "node " << i;
      ++nodes_compared;
    }
    ASSERT_EQ(a.gain_found, b.gain_found);
    if (!a.gain_found) break;
    EXPECT_EQ(a.next.position, b.next.position);
    robot = a.next;
  }
  EXPECT_GE(nodes_compared, 100u);
  // The planners drew the same samples and made the same checks; the field answered most of them.
  EXPECT_EQ(field_planner.stats().node_checks.count, checks_planner.stats().node_checks.count);
  EXPECT_EQ(field_planner.stats().edge_checks.count, checks_planner.stats().edge_checks.count);
  const ClearanceCounts counts = field_map.field_clearance()->counts();
  EXPECT_GE(counts.balls_by_field, counts.balls_by_map);
}

}  // namespace
}  // namespace umbra::explore
