// Tests of the next-best-view planner (examples/explore/nbv_planner.hpp).
//
// On a test double of the map (a free box with one solid pillar and a gain
// that is a known function of the view's position) every tree node is
// recomputed from its definition: inside the bounds, at most one extension
// from its parent, its ball and its edge clear of the pillar (checked with
// the tests' own shape oracle), path length the sum of its edges, gain the
// double's value, score the parent's plus the gain discounted by
// exp(-lambda * path length); the step flies to the first node of the branch
// to the best score. On a real umbra map of the plant seen from the start,
// every node's ball and every edge's capsule is checked voxel by voxel
// (brute force over the voxels whose cubes meet the shape) and against the
// scene's true distances.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "nbv_planner.hpp"
#include "support/shape_oracle.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/industrial_scene.hpp"
#include "umbra_exploration_map.hpp"

namespace umbra::explore {
namespace {

/// A 10 x 10 x 4 m room, everything known free except a solid pillar; the
/// gain of a view grows with x (and is 0 for x < 3).
class FakeMap final : public ExplorationMap {
 public:
  static constexpr double kPillarMin[3] = {4.0, 4.0, 0.0};
  static constexpr double kPillarMax[3] = {6.0, 6.0, 4.0};

  static test::Cube pillar() {
    return {{kPillarMin[0], kPillarMin[1], kPillarMin[2]}, {kPillarMax[0], kPillarMax[1], kPillarMax[2]}};
  }
  static double gain_at(Vec3d p) { return p.x < 3.0 ? 0.0 : 0.7 * (p.x - 3.0) + 0.1 * p.y; }

  [[nodiscard]] std::string name() const override { return "fake"; }
  [[nodiscard]] double resolution() const override { return 0.1; }
  void assume_free(const Sphere&) override {}
  void insert(Vec3f, std::span<const Vec3f>, double) override {}
  [[nodiscard]] bool is_free(const Sphere& ball) const override {
    ++ball_checks;
    return !test::meets(ball, pillar());
  }
  [[nodiscard]] bool is_free(const Capsule& path) const override {
    ++capsule_checks;
    return !test::meets(path, pillar());
  }
  [[nodiscard]] double gain(const Frustum& view) const override {
    ++gains;
    return gain_at(view.origin);
  }
  void for_each_free_node(FunctionRef<void(Vec3d, Vec3d)>) const override {}
  [[nodiscard]] std::size_t memory_bytes() const override { return 0; }

  mutable int ball_checks = 0;
  mutable int capsule_checks = 0;
  mutable int gains = 0;
};

/// Free everywhere (but for the balls `blocked` refuses), nothing inserted,
/// the gain of a view given by `view_gain`: the open-space test doubles.
class OpenMap final : public ExplorationMap {
 public:
  using Gain = std::function<double(const Frustum&)>;
  using Blocked = std::function<bool(const Sphere&)>;
  OpenMap(std::string name, Gain view_gain, Blocked blocked = {})
      : name_(std::move(name)), view_gain_(std::move(view_gain)), blocked_(std::move(blocked)) {}
  [[nodiscard]] std::string name() const override { return name_; }
  [[nodiscard]] double resolution() const override { return 0.1; }
  void assume_free(const Sphere&) override {}
  void insert(Vec3f, std::span<const Vec3f>, double) override {}
  [[nodiscard]] bool is_free(const Sphere& ball) const override { return !blocked_ || !blocked_(ball); }
  [[nodiscard]] bool is_free(const Capsule&) const override { return true; }
  [[nodiscard]] double gain(const Frustum& view) const override {
    ++gains;
    return view_gain_(view);
  }
  void for_each_free_node(FunctionRef<void(Vec3d, Vec3d)>) const override {}
  [[nodiscard]] std::size_t memory_bytes() const override { return 0; }

  mutable int gains = 0;

 private:
  std::string name_;
  Gain view_gain_;
  Blocked blocked_;
};

PlannerConfig room_config() {
  PlannerConfig config;
  config.bounds = Aabb{{0.5, 0.5, 0.5}, {9.5, 9.5, 3.5}};
  config.initial_nodes = 60;  // the tree grows to max_nodes
  config.max_nodes = 60;
  config.lambda = 0.4;
  config.min_gain = 0.5;  // FakeMap's gains below it count as none in a score
  config.yaw_samples = 1;  // one gain per node (FakeMap's gain ignores the heading)
  return config;
}

/// Checks every node of `planner`'s last tree against its definition.
void expect_tree_as_defined(const NbvPlanner& planner, const PlannerConfig& config, const Pose& robot) {
  const auto& tree = planner.tree();
  ASSERT_GE(tree.size(), 2u);
  EXPECT_EQ(tree[0].pose.position, robot.position);
  EXPECT_EQ(tree[0].parent, -1);
  for (std::size_t i = 1; i < tree.size(); ++i) {
    SCOPED_TRACE("node " + std::to_string(i));
    const auto& node = tree[i];
    ASSERT_GE(node.parent, 0);
    ASSERT_LT(std::size_t(node.parent), i);
    const auto& up = tree[std::size_t(node.parent)];
    const Vec3d p = node.pose.position;
    const double edge = (p - up.pose.position).norm();
    EXPECT_LE(edge, config.extension_range + 1e-9);
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_GE(p[a], config.bounds.min[a]);
      EXPECT_LE(p[a], config.bounds.max[a]);
    }
    EXPECT_FALSE(test::meets(Sphere{p, config.check_radius()}, FakeMap::pillar()));
    EXPECT_FALSE(test::meets(Capsule{up.pose.position, p, config.check_radius()}, FakeMap::pillar()));
    EXPECT_NEAR(node.path_length, up.path_length + edge, 1e-9);
    EXPECT_DOUBLE_EQ(node.gain, FakeMap::gain_at(p));
    const double useful = FakeMap::gain_at(p) >= config.min_gain ? FakeMap::gain_at(p) : 0.0;
    EXPECT_NEAR(node.score, up.score + useful * std::exp(-config.lambda * node.path_length), 1e-9);
  }
}

TEST(NbvPlanner, TreeNodesAreWhatTheyClaimAndTheStepIsTheBestBranchsFirstNode) {
  const FakeMap map;
  const PlannerConfig config = room_config();
  NbvPlanner planner(config, 7);
  const Pose robot{{2.0, 2.0, 2.0}, 0.0};
  const PlanStep step = planner.plan(map, robot);
  expect_tree_as_defined(planner, config, robot);
  const auto& tree = planner.tree();
  EXPECT_EQ(step.tree_nodes, int(tree.size()) - 1);
  EXPECT_EQ(step.tree_nodes, config.max_nodes);
  ASSERT_TRUE(step.gain_found);

  std::size_t best = 1;
  for (std::size_t i = 1; i < tree.size(); ++i) {
    if (tree[i].score > tree[best].score) best = i;
  }
  EXPECT_DOUBLE_EQ(step.best_score, tree[best].score);
  EXPECT_DOUBLE_EQ(step.best_gain, tree[best].gain);
  std::size_t first = best;
  while (tree[first].parent != 0) first = std::size_t(tree[first].parent);
  EXPECT_EQ(step.next.position, tree[first].pose.position);
  EXPECT_EQ(step.next.yaw, tree[first].pose.yaw);

  // Every node cost one gain, and every query was counted.
  EXPECT_EQ(planner.stats().gains.count, std::uint64_t(map.gains));
  EXPECT_EQ(std::uint64_t(map.gains), tree.size() - 1);
  EXPECT_EQ(planner.stats().node_checks.count, std::uint64_t(map.ball_checks));
  EXPECT_EQ(planner.stats().edge_checks.count, std::uint64_t(map.capsule_checks));
  EXPECT_GT(map.ball_checks, map.capsule_checks);  // some samples landed in the pillar
}

TEST(NbvPlanner, NextStepKeepsTheRestOfTheBestBranch) {
  const FakeMap map;
  const PlannerConfig config = room_config();
  NbvPlanner planner(config, 11);
  const Pose robot{{2.0, 2.0, 2.0}, 0.0};
  const PlanStep first = planner.plan(map, robot);
  ASSERT_TRUE(first.gain_found);
  std::vector<Vec3d> rest;
  {
    const auto& tree = planner.tree();
    std::size_t best = 1;
    for (std::size_t i = 1; i < tree.size(); ++i) {
      if (tree[i].score > tree[best].score) best = i;
    }
    for (std::size_t i = best; tree[i].parent != 0; i = std::size_t(tree[i].parent)) rest.push_back(tree[i].pose.position);
  }
  planner.plan(map, first.next);
  expect_tree_as_defined(planner, config, first.next);
  const auto& tree = planner.tree();
  ASSERT_GT(tree.size(), rest.size());
  // Nodes 1..n are the old branch after its first node, in order.
  for (std::size_t k = 0; k < rest.size(); ++k) EXPECT_EQ(tree[k + 1].pose.position, rest[rest.size() - 1 - k]);
}

TEST(NbvPlanner, DiscountingTurnsTheRobotTowardsNearGainWhenLambdaIsLarge) {
  // A corridor along x (1 m wide and high) with the robot in the middle:
  // 1 m^3 of gain at least 1 m to the west (x < 4), 100 m^3 at least 3 m to
  // the east (x > 8). Without discount the first step goes east. With
  // lambda = 5/m a west node within 1.6 m of path scores at least e^-8 =
  // 3.4e-4, an east node adds at most 100 e^-15 = 3e-5 per node (and its
  // descendants less and less): the first step goes west.
  const OpenMap map("two sides", [](const Frustum& view) {
    return view.origin.x > 8.0 ? 100.0 : (view.origin.x < 4.0 ? 1.0 : 0.0);
  });
  PlannerConfig config = room_config();
  config.bounds = Aabb{{0.5, 4.5, 1.5}, {9.5, 5.5, 2.5}};
  config.max_nodes = 150;
  config.initial_nodes = 150;
  const Pose robot{{5.0, 5.0, 2.0}, 0.0};
  auto first_step_x = [&](double lambda, std::uint32_t seed) {
    config.lambda = lambda;
    NbvPlanner planner(config, seed);
    const PlanStep step = planner.plan(map, robot);
    EXPECT_TRUE(step.gain_found);
    return step.next.position.x;
  };
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    EXPECT_GT(first_step_x(0.0, seed), 5.0);
    EXPECT_LT(first_step_x(5.0, seed), 5.0);
  }
}

TEST(NbvPlanner, NoGainMeansDoneAndSameSeedSameTree) {
  const OpenMap map("no gain", [](const Frustum&) { return 0.1; });
  const PlannerConfig config = room_config();
  NbvPlanner a(config, 5);
  NbvPlanner b(config, 5);
  const Pose robot{{2.0, 2.0, 2.0}, 0.0};
  EXPECT_FALSE(a.plan(map, robot).gain_found);  // 0.1 < min_gain everywhere
  b.plan(map, robot);
  ASSERT_EQ(a.tree().size(), b.tree().size());
  for (std::size_t i = 0; i < a.tree().size(); ++i) EXPECT_EQ(a.tree()[i].pose.position, b.tree()[i].pose.position);
}

TEST(NbvPlanner, GrowsOnWhenNoGainIsNearAndStopsAtTheFirstGain) {
  // A 40 m corridor with gain only beyond x = 25; the robot at x = 2. A tree
  // of max_nodes = 20 cannot reach it: the tree grows on until a node there
  // has gain, and the step is the first edge towards it.
  const OpenMap map("far gain", [](const Frustum& view) { return view.origin.x > 25.0 ? 2.0 : 0.0; });
  PlannerConfig config = room_config();
  config.bounds = Aabb{{0.5, 4.0, 1.0}, {39.5, 6.0, 3.0}};
  config.initial_nodes = 20;
  config.max_nodes = 20;
  config.max_nodes_no_gain = 2000;
  const Pose robot{{2.0, 5.0, 2.0}, 0.0};
  NbvPlanner planner(config, 9);
  const PlanStep step = planner.plan(map, robot);
  ASSERT_TRUE(step.gain_found);
  EXPECT_TRUE(step.grown_on);
  EXPECT_EQ(planner.stats().grown_on, 1u);
  const auto& tree = planner.tree();
  EXPECT_GT(tree.size(), 21u);
  EXPECT_LT(tree.size(), 2001u);
  // It stopped at the first node with gain: the newest node, the only one.
  EXPECT_GT(tree.back().pose.position.x, 25.0);
  for (std::size_t i = 1; i + 1 < tree.size(); ++i) EXPECT_LE(tree[i].pose.position.x, 25.0);
  EXPECT_GT(step.next.position.x, robot.position.x);

  // With no room to grow on, the same situation ends the exploration.
  config.max_nodes_no_gain = config.max_nodes;
  config.final_min_gain = config.min_gain;
  NbvPlanner capped(config, 9);
  const PlanStep done = capped.plan(map, robot);
  EXPECT_FALSE(done.gain_found);
  EXPECT_EQ(done.tree_nodes, config.max_nodes);
}

TEST(NbvPlanner, OnlyCrumbsLeftLowerTheThresholdAndCountThemAgain) {
  // Every view sees 0.3 m^3: below min_gain (1), above final_min_gain
  // (0.125). The grown-on tree finds nothing; halving the threshold twice
  // (0.5, 0.25) makes the crumbs count, and scores follow the new threshold.
  const OpenMap map("crumbs", [](const Frustum&) { return 0.3; });
  PlannerConfig config = room_config();
  config.min_gain = 1.0;
  config.final_min_gain = 0.125;
  config.initial_nodes = 15;
  config.max_nodes = 30;
  config.max_nodes_no_gain = 60;
  NbvPlanner planner(config, 4);
  const Pose robot{{2.0, 2.0, 2.0}, 0.0};
  const PlanStep step = planner.plan(map, robot);
  EXPECT_TRUE(step.gain_found);
  EXPECT_TRUE(step.grown_on);
  EXPECT_EQ(planner.stats().threshold_lowered, 2u);
  EXPECT_DOUBLE_EQ(planner.gain_threshold(), 0.25);
  const auto& tree = planner.tree();
  EXPECT_EQ(tree.size(), 61u);
  for (std::size_t i = 1; i < tree.size(); ++i) {
    const auto& up = tree[std::size_t(tree[i].parent)];
    EXPECT_NEAR(tree[i].score, up.score + 0.3 * std::exp(-config.lambda * tree[i].path_length), 1e-12);
  }
  // The threshold stays low for the next steps.
  EXPECT_TRUE(planner.plan(map, step.next).gain_found);
  EXPECT_EQ(planner.stats().threshold_lowered, 2u);
}

TEST(NbvPlanner, TrappedRobotFliesBackTheWayItCame) {
  // Free everywhere except the balls around `trap` (a surface seen after the
  // robot got there): planning from there goes back to the last pose it
  // planned from, and from an empty history nowhere.
  Vec3d trap{50.0, 50.0, 50.0};
  const OpenMap map("trap", [](const Frustum&) { return 2.0; },
                    [&trap](const Sphere& ball) { return (ball.center - trap).norm() <= 0.2; });
  const PlannerConfig config = room_config();
  NbvPlanner planner(config, 2);
  const Pose start{{2.0, 2.0, 2.0}, 0.0};
  const PlanStep first = planner.plan(map, start);
  ASSERT_TRUE(first.gain_found);
  EXPECT_FALSE(first.backtracked);
  trap = first.next.position;
  const PlanStep back = planner.plan(map, first.next);
  EXPECT_TRUE(back.gain_found);
  EXPECT_TRUE(back.backtracked);
  EXPECT_EQ(back.next.position, start.position);
  EXPECT_EQ(planner.stats().backtracks, 1u);
  EXPECT_EQ(planner.tree().size(), 1u);  // no tree grown from a trap

  NbvPlanner fresh(config, 2);
  trap = start.position;
  EXPECT_FALSE(fresh.plan(map, start).gain_found);
}

/// A view's gain by its heading: most looking along +x.
double heading_gain(const Frustum& view) { return 1.0 + 2.0 * std::cos(view.yaw); }

TEST(NbvPlanner, EachNodeKeepsTheBestOfItsSampledHeadings) {
  PlannerConfig config = room_config();
  config.yaw_samples = 4;
  const OpenMap map("heading", heading_gain);
  NbvPlanner planner(config, 11);
  planner.plan(map, Pose{{2.0, 2.0, 2.0}, 0.0});
  const auto& tree = planner.tree();
  ASSERT_EQ(tree.size(), std::size_t(config.max_nodes) + 1);
  EXPECT_EQ(std::size_t(map.gains), 4 * (tree.size() - 1)) << "four headings per node, no gain computed twice";
  double worst = 3.0;
  for (std::size_t i = 1; i < tree.size(); ++i) {
    // The node's own gain is its heading's, and no other of the four evenly
    // spaced headings from it would have had more.
    const double yaw = tree[i].pose.yaw;
    const Frustum view = config.camera.frustum(tree[i].pose);
    EXPECT_DOUBLE_EQ(tree[i].gain, heading_gain(view));
    for (int k = 1; k < 4; ++k) {
      const Frustum other = config.camera.frustum(Pose{tree[i].pose.position, yaw + k * std::numbers::pi / 2.0});
      EXPECT_GE(tree[i].gain, heading_gain(other)) << "node " << i;
    }
    worst = std::min(worst, tree[i].gain);
  }
  // The best of four headings 90 degrees apart is within 45 degrees of +x.
  EXPECT_GE(worst, 1.0 + 2.0 * std::cos(std::numbers::pi / 4.0) - 1e-9);
}

constexpr double planner_extension_range = PlannerConfig{}.extension_range;

/// Plans once from `robot` (with gain everywhere), then returns a pose of that
/// tree `away` metres or more from the robot and off the chosen branch: a pose the planner remembers.
Pose remembered_pose(NbvPlanner& planner, const ExplorationMap& map, const Pose& robot, double away, PlanStep& first) {
  first = planner.plan(map, robot);
  const auto& tree = planner.tree();
  std::size_t best = 1;
  for (std::size_t i = 1; i < tree.size(); ++i) {
    if (tree[i].score > tree[best].score) best = i;
  }
  std::vector<std::size_t> branch;
  for (std::size_t i = best; i != 0; i = std::size_t(tree[i].parent)) branch.push_back(i);
  const auto off_branch = [&](std::size_t i) { return std::find(branch.begin(), branch.end(), i) == branch.end(); };
  // A far node off the branch with no later such node near it: the memory
  // keeps one pose per neighbourhood, the newest.
  for (std::size_t i = tree.size() - 1; i >= 1; --i) {
    if ((tree[i].pose.position - robot.position).norm() < away || !off_branch(i)) continue;
    bool newest = true;
    for (std::size_t j = i + 1; j < tree.size(); ++j) {
      newest = newest && !(off_branch(j) && (tree[j].pose.position - tree[i].pose.position).norm() <
                                                 planner_extension_range);
    }
    if (newest) return tree[i].pose;
  }
  ADD_FAILURE() << "no node " << away << " m away off the branch";
  return robot;
}

/// A 19 x 9 x 3 m room; gains from 1 m^3 count.
PlannerConfig routing_room_config() {
  PlannerConfig config = room_config();
  config.bounds = Aabb{{0.5, 0.5, 0.5}, {19.5, 9.5, 3.5}};
  config.min_gain = 1.0;
  config.final_min_gain = 1.0;
  return config;
}

/// 40 everywhere until a goal is set (x >= 0); then 40 at the goal and 1.2 elsewhere.
double goal_gain(Vec3d goal_position, const Frustum& view) {
  if (goal_position.x < 0.0) return 40.0;
  return view.origin == goal_position ? 40.0 : 1.2;
}

TEST(NbvPlanner, RoutesOverTheRoadmapToARememberedPoseThatOutratesTheLocalTree) {
  // First step: gain 40 everywhere. Then only crumbs (1.2, above the
  // threshold) but at one remembered pose `goal` far away, which keeps its
  // 40: 40 / (distance + overhead) beats 1.2 / (1.5 + overhead), so the
  // robot flies the roadmap there edge by edge, facing its way, and ends at
  // the goal's position and heading, in legs that cut the roadmap's corners.
  PlannerConfig config = routing_room_config();
  Vec3d goal_position{-1, -1, -1};
  const OpenMap map("goal far away", [&](const Frustum& view) { return goal_gain(goal_position, view); });
  NbvPlanner planner(config, 21);
  const Pose start{{2.0, 5.0, 2.0}, 0.0};
  PlanStep step;
  const Pose goal = remembered_pose(planner, map, start, 6.0, step);
  goal_position = goal.position;

  Pose robot = step.next;
  int routed_steps = 0;
  for (int k = 0; k < 50 && robot.position != goal.position; ++k) {
    step = planner.plan(map, robot);
    ASSERT_TRUE(step.gain_found);
    ASSERT_TRUE(step.routed) << "step " << k << " left the route";
    // Legs cut corners of the roadmap (all free here) up to four extensions long.
    EXPECT_LE((step.next.position - robot.position).norm(), 4.0 * config.extension_range + 1e-9);
    if (step.next.position != goal.position) {
      const Vec3d way = step.next.position - robot.position;
      EXPECT_NEAR(step.next.yaw, std::atan2(way.y, way.x), 1e-12) << "faces along its way";
    }
    robot = step.next;
    ++routed_steps;
  }
  EXPECT_EQ(robot.position, goal.position);
  EXPECT_DOUBLE_EQ(robot.yaw, goal.yaw);
  EXPECT_EQ(planner.stats().routes, 1u);
  EXPECT_EQ(planner.stats().route_steps, std::uint64_t(routed_steps));
  EXPECT_GE(routed_steps, 1);

  // Without routing the robot stays with the local crumbs.
  config.route_to_memory = false;
  NbvPlanner local(config, 21);
  goal_position = {-1, -1, -1};
  remembered_pose(local, map, start, 6.0, step);
  goal_position = goal.position;
  EXPECT_FALSE(local.plan(map, step.next).routed);
  EXPECT_EQ(local.stats().routes, 0u);
}

TEST(NbvPlanner, ARouteBlockedByNewSurfacesIsDroppedAndThePlannerPlansAfresh) {
  PlannerConfig config = routing_room_config();
  Vec3d goal_position{-1, -1, -1};
  std::vector<Vec3d> walls;  // balls there are blocked
  const OpenMap map(
      "blocked route",
      [&](const Frustum& view) { return goal_gain(goal_position, view); },
      [&](const Sphere& ball) { return std::find(walls.begin(), walls.end(), ball.center) != walls.end(); });
  NbvPlanner planner(config, 21);
  const Pose start{{2.0, 5.0, 2.0}, 0.0};
  PlanStep step;
  const Pose goal = remembered_pose(planner, map, start, 6.0, step);
  std::vector<Vec3d> first_tree;
  for (const auto& node : planner.tree()) first_tree.push_back(node.pose.position);
  goal_position = goal.position;
  const Pose robot = step.next;
  step = planner.plan(map, robot);
  ASSERT_TRUE(step.routed);
  ASSERT_EQ(planner.stats().routes, 1u);
  if (step.next.position == goal.position) GTEST_SKIP() << "the route was one leg";
  // Surfaces seen at every node of the first tree but where the robot is:
  // no leg of the route is free, so it is dropped, and the step is the local tree's.
  const Pose here = step.next;
  for (const Vec3d& p : first_tree) {
    if (p != here.position) walls.push_back(p);
  }
  step = planner.plan(map, here);
  EXPECT_GE(planner.stats().routes_blocked, 1u);
  EXPECT_FALSE(step.routed);
  EXPECT_TRUE(step.gain_found);
  EXPECT_EQ(std::find(walls.begin(), walls.end(), step.next.position), walls.end());
}

TEST(NbvPlanner, BadConfigIsRefusedByName) {
  PlannerConfig config = room_config();
  config.max_nodes = config.initial_nodes - 1;
  try {
    NbvPlanner planner(config, 1);
    FAIL() << "accepted max_nodes < initial_nodes";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("max_nodes"), std::string::npos) << error.what();
  }
  config = room_config();
  config.yaw_samples = 0;
  EXPECT_THROW(NbvPlanner(config, 1), std::invalid_argument);
}

/// Every voxel whose cube meets `shape` is known free in `map` (brute force).
template <typename Shape>
bool every_voxel_free(const OccupancyMap& map, const Shape& shape, Vec3d low, Vec3d high) {
  const Key first = map.key(low);
  const Key last = map.key(high);
  const double half = 0.5 * map.resolution();
  for (std::uint32_t z = first.z; z <= last.z; ++z) {
    for (std::uint32_t y = first.y; y <= last.y; ++y) {
      for (std::uint32_t x = first.x; x <= last.x; ++x) {
        const Vec3d c = map.grid().center(Key{x, y, z});
        const test::Cube cube{c - Vec3d{half, half, half}, c + Vec3d{half, half, half}};
        if (test::meets(shape, cube) && map.state(c) != OccupancyState::free) return false;
      }
    }
  }
  return true;
}

TEST(NbvPlanner, OnUmbraNodesAndEdgesAreFreeVoxelByVoxelAndClearOfThePlant) {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  UmbraExplorationMap map(UmbraMapOptions{});
  map.assume_free(Sphere{plant.start, 1.0});
  sim::DepthCameraModel camera;
  camera.width = 96;
  camera.height = 50;
  camera.emit_no_return = true;
  camera.no_return_range = camera.max_range + 1.0;
  std::vector<Vec3f> points;
  for (int k = 0; k < 8; ++k) {
    const double yaw = 2.0 * std::numbers::pi * k / 8.0;
    sim::simulate_depth_image(plant.scene, {plant.start, yaw, 0.0}, camera, points);
    map.insert(Vec3f(plant.start), points, camera.max_range);
  }

  PlannerConfig config;
  config.bounds = Aabb{plant.interior.min, plant.interior.max};
  config.initial_nodes = 30;
  config.max_nodes = 30;
  NbvPlanner planner(config, 1);
  Pose robot{plant.start, 0.0};
  int nodes_checked = 0;
  for (int step = 0; step < 3; ++step) {
    const PlanStep planned = planner.plan(map, robot);
    const auto& tree = planner.tree();
    for (std::size_t i = 1; i < tree.size(); ++i) {
      SCOPED_TRACE("step " + std::to_string(step) + ", node " + std::to_string(i));
      const Vec3d p = tree[i].pose.position;
      const Vec3d q = tree[std::size_t(tree[i].parent)].pose.position;
      const double r = config.check_radius();
      const Vec3d reach{r, r, r};
      EXPECT_TRUE(every_voxel_free(map.map(), Sphere{p, r}, p - reach, p + reach));
      Vec3d low = p;
      Vec3d high = p;
      for (std::size_t a = 0; a < 3; ++a) {
        low[a] = std::min(p[a], q[a]) - r;
        high[a] = std::max(p[a], q[a]) + r;
      }
      EXPECT_TRUE(every_voxel_free(map.map(), Capsule{q, p, r}, low, high));
      // The map's free space is the plant's: the robot's ball there touches nothing.
      EXPECT_GE(plant.scene.distance_to_nearest_surface(p), config.robot_radius);
      EXPECT_FALSE(plant.scene.is_inside_solid(p));
      ++nodes_checked;
    }
    if (!planned.gain_found) break;
    robot = planned.next;
  }
  EXPECT_GE(nodes_checked, 30);
}

}  // namespace
}  // namespace umbra::explore
