// Tests of the procedural scene and the simulated LiDAR.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {
namespace {

Vec3d unit(Vec3d v) { return v / v.norm(); }

Scene one_box(const Box& box) {
  Scene scene;
  scene.add_box(box);
  return scene;
}

Scene one_cylinder(const Cylinder& cylinder) {
  Scene scene;
  scene.add_cylinder(cylinder);
  return scene;
}

// --- scene -----------------------------------------------------------------

TEST(SceneIntersect, AxisAlignedRayIntoBox) {
  const Scene scene = one_box({{1.0, -1.0, -1.0}, {2.0, 1.0, 1.0}});
  const auto hit = scene.intersect({0, 0, 0}, {1, 0, 0}, 10.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 1.0, 1e-12);
  // From the far side the near face is x = 2.
  const auto back = scene.intersect({5, 0, 0}, {-1, 0, 0}, 10.0);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(*back, 3.0, 1e-12);
}

TEST(SceneIntersect, ObliqueRayIntoBox) {
  // Direction (3, 4, 0) / 5 reaches the face x = 3 at t = 5, where y = 4 is inside the box.
  const Scene scene = one_box({{3.0, -10.0, -1.0}, {10.0, 10.0, 1.0}});
  const auto hit = scene.intersect({0, 0, 0}, unit({3, 4, 0}), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 5.0, 1e-12);
  // Diagonal in 3D into the corner region: (1,1,1)/sqrt(3) enters the box
  // [1,2]^3 at its corner (1,1,1), t = sqrt(3).
  const Scene cube = one_box({{1, 1, 1}, {2, 2, 2}});
  const auto corner = cube.intersect({0, 0, 0}, unit({1, 1, 1}), 100.0);
  ASSERT_TRUE(corner.has_value());
  EXPECT_NEAR(*corner, std::sqrt(3.0), 1e-12);
}

TEST(SceneIntersect, CylinderSideAndCap) {
  const Scene scene = one_cylinder({5.0, 0.0, 1.0, 0.0, 2.0});
  // Straight at the side.
  auto hit = scene.intersect({0, 0, 1}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  // Oblique through the axis: the ray from (1, -3, 1) along (4, 3, 0)/5 passes
  // the centre (5, 0) at t = 5, so it enters the side at t = 5 - radius = 4.
  hit = scene.intersect({1, -3, 1}, unit({4, 3, 0}), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 4.0, 1e-12);
  // Down onto the top cap.
  hit = scene.intersect({5, 0, 5}, {0, 0, -1}, 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 3.0, 1e-12);
  // Oblique onto the cap: from (2, 0, 6) along (3, 0, -4)/5 reaches (5, 0, 2) at t = 5;
  // at the rim x = 4 it is still at z = 3.33, above the cylinder.
  hit = scene.intersect({2, 0, 6}, unit({3, 0, -4}), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 5.0, 1e-12);
  // Grazing the side tangentially at y = radius still touches it.
  hit = scene.intersect({0, 1, 1}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 5.0, 1e-6);
}

TEST(SceneIntersect, Misses) {
  const Scene scene = one_box({{1.0, -1.0, -1.0}, {2.0, 1.0, 1.0}});
  EXPECT_FALSE(scene.intersect({0, 0, 0}, {-1, 0, 0}, 100.0).has_value());  // behind
  EXPECT_FALSE(scene.intersect({0, 2, 0}, {1, 0, 0}, 100.0).has_value());   // beside
  EXPECT_FALSE(
      scene.intersect({0, 0, 0}, unit({1, 3, 0}), 100.0).has_value());  // passes above y = 1
  const Scene pillar = one_cylinder({5.0, 0.0, 1.0, 0.0, 2.0});
  EXPECT_FALSE(pillar.intersect({0, 1.01, 1}, {1, 0, 0}, 100.0).has_value());
  EXPECT_FALSE(pillar.intersect({0, 0, 2.5}, {1, 0, 0}, 100.0).has_value());  // over the top
  EXPECT_FALSE(Scene{}.intersect({0, 0, 0}, {1, 0, 0}, 100.0).has_value());
}

TEST(SceneIntersect, MaxRangeCutOff) {
  const Scene scene = one_box({{1.0, -1.0, -1.0}, {2.0, 1.0, 1.0}});
  EXPECT_FALSE(scene.intersect({0, 0, 0}, {1, 0, 0}, 0.999).has_value());
  const auto at_limit = scene.intersect({0, 0, 0}, {1, 0, 0}, 1.0);
  ASSERT_TRUE(at_limit.has_value());
  EXPECT_DOUBLE_EQ(*at_limit, 1.0);
}

TEST(SceneIntersect, NearestOfSeveralPrimitivesWins) {
  Scene scene;
  scene.add_box({{4.0, -1.0, -1.0}, {5.0, 1.0, 1.0}});
  scene.add_cylinder({2.5, 0.0, 0.5, -1.0, 1.0});
  scene.add_box({{8.0, -1.0, -1.0}, {9.0, 1.0, 1.0}});
  const auto hit = scene.intersect({0, 0, 0}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 2.0, 1e-12);
}

TEST(SceneIntersect, RayStartingInsideASolidReturnsZero) {
  const Scene scene = one_box({{-1, -1, -1}, {1, 1, 1}});
  const auto hit = scene.intersect({0, 0, 0}, {0, 0, 1}, 10.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(*hit, 0.0);
  const Scene pillar = one_cylinder({0, 0, 1, 0, 2});
  const auto inside = pillar.intersect({0.5, 0, 1}, {1, 0, 0}, 10.0);
  ASSERT_TRUE(inside.has_value());
  EXPECT_EQ(*inside, 0.0);
}

TEST(SceneIntersect, RejectsBadArguments) {
  const Scene scene = one_box({{1, 1, 1}, {2, 2, 2}});
  EXPECT_THROW((void)scene.intersect({0, 0, 0}, {1, 1, 0}, 10.0), std::invalid_argument);
  EXPECT_THROW((void)scene.intersect({NAN, 0, 0}, {1, 0, 0}, 10.0), std::invalid_argument);
  EXPECT_THROW((void)scene.intersect({0, 0, 0}, {1, 0, 0}, -1.0), std::invalid_argument);
  EXPECT_THROW((void)scene.intersect({0, 0, 0}, {1, 0, 0}, NAN), std::invalid_argument);
}

TEST(Scene, RejectsDegeneratePrimitives) {
  Scene scene;
  EXPECT_THROW(scene.add_box({{0, 0, 0}, {1, 0, 1}}), std::invalid_argument);
  EXPECT_THROW(scene.add_box({{0, 0, 0}, {1, INFINITY, 1}}), std::invalid_argument);
  EXPECT_THROW(scene.add_cylinder({0, 0, 0.0, 0, 1}), std::invalid_argument);
  EXPECT_THROW(scene.add_cylinder({0, 0, 1.0, 2, 1}), std::invalid_argument);
  EXPECT_TRUE(scene.empty());
  EXPECT_THROW((void)scene.bounds(), std::logic_error);
}

TEST(Scene, InsideAndDistanceToSurface) {
  Scene scene;
  scene.add_box({{0, 0, 0}, {2, 2, 2}});
  scene.add_cylinder({10, 0, 1, 0, 2});
  EXPECT_TRUE(scene.is_inside_solid({1, 1, 1}));
  EXPECT_TRUE(scene.is_inside_solid({2, 2, 2}));  // closed: the surface counts
  EXPECT_TRUE(scene.is_inside_solid({10.5, 0.5, 1}));
  EXPECT_FALSE(scene.is_inside_solid({5, 0, 1}));
  EXPECT_FALSE(scene.is_inside_solid({10.8, 0.8, 1}));  // in the bounding square, outside the disc

  EXPECT_NEAR(scene.distance_to_nearest_surface({1, 1, 1}), 1.0, 1e-12);             // box centre
  EXPECT_NEAR(scene.distance_to_nearest_surface({3, 1, 1}), 1.0, 1e-12);             // off a face
  EXPECT_NEAR(scene.distance_to_nearest_surface({3, 3, 3}), std::sqrt(3.0), 1e-12);  // off a corner
  EXPECT_NEAR(scene.distance_to_nearest_surface({10, 0, 1}), 1.0, 1e-12);            // pillar axis
  EXPECT_NEAR(scene.distance_to_nearest_surface({10, 3, 1}), 2.0, 1e-12);  // beside the pillar
  EXPECT_NEAR(scene.distance_to_nearest_surface({10, 4, 6}), 5.0, 1e-12);  // off the rim: (3, 4)

  const Box bounds = scene.bounds();
  EXPECT_EQ(bounds.min, (Vec3d{0, -1, 0}));
  EXPECT_EQ(bounds.max, (Vec3d{11, 2, 2}));
}

// --- demo scene and path -----------------------------------------------------

TEST(DemoScene, IsTheDescribedBuilding) {
  const Scene scene = make_demo_scene();
  const Box bounds = scene.bounds();
  EXPECT_EQ(bounds.min, (Vec3d{0.0, 0.0, -0.2}));
  EXPECT_EQ(bounds.max, (Vec3d{20.0, 12.0, 3.2}));
  EXPECT_GE(scene.cylinders().size(), 2u);
  // Deterministic: built the same way twice.
  const Scene again = make_demo_scene();
  ASSERT_EQ(again.boxes().size(), scene.boxes().size());
  for (std::size_t i = 0; i < scene.boxes().size(); ++i) {
    EXPECT_EQ(again.boxes()[i].min, scene.boxes()[i].min);
    EXPECT_EQ(again.boxes()[i].max, scene.boxes()[i].max);
  }
  // The corridor is open from end to end at 1.2 m, and a door leads north
  // from it into the meeting room.
  const auto along = scene.intersect({0.5, 6.0, 1.2}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(along.has_value());
  EXPECT_NEAR(*along, 19.3, 1e-9);
  const auto through_door = scene.intersect({10.0, 6.0, 1.2}, {0, 1, 0}, 100.0);
  ASSERT_TRUE(through_door.has_value());
  EXPECT_NEAR(*through_door, 5.8, 1e-9);  // the north outer wall at y = 11.8
  const auto wall = scene.intersect({5.0, 6.0, 1.2}, {0, 1, 0}, 100.0);
  ASSERT_TRUE(wall.has_value());
  EXPECT_NEAR(*wall, 1.0, 1e-9);  // the corridor wall at y = 7
}

TEST(DemoScene, PathPosesAreInFreeSpaceInsideTheBuilding) {
  const Scene scene = make_demo_scene();
  const auto path = demo_path();
  EXPECT_GE(path.size(), 8u);
  EXPECT_LE(path.size(), 12u);
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Vec3d p = path[i].position;
    SCOPED_TRACE("pose " + std::to_string(i));
    EXPECT_FALSE(scene.is_inside_solid(p));
    EXPECT_GE(scene.distance_to_nearest_surface(p), 0.3);
    EXPECT_NEAR(p.z, 1.2, 1e-12);
    // Enclosed: every axis direction runs into the building within its size.
    for (const Vec3d direction : {Vec3d{1, 0, 0}, Vec3d{-1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, -1, 0},
                                  Vec3d{0, 0, 1}, Vec3d{0, 0, -1}}) {
      EXPECT_TRUE(scene.intersect(p, direction, 25.0).has_value());
    }
  }
}

TEST(DemoScene, ScanFromEveryPoseIsNonEmpty) {
  const Scene scene = make_demo_scene();
  const LidarModel model;
  std::vector<Vec3f> points;
  for (const SensorPose& pose : demo_path()) {
    simulate_scan(scene, pose, model, points);
    // Indoors every beam hits something (floor, walls or ceiling).
    EXPECT_EQ(points.size(), model.beam_count());
  }
}

// --- LiDAR -------------------------------------------------------------------

LidarModel small_model() {
  LidarModel model;
  model.rings = 16;
  model.azimuth_steps = 180;
  return model;
}

const SensorPose kCorridorPose{{4.0, 6.0, 1.2}, 0.3};

TEST(Lidar, SameSeedGivesIdenticalPoints) {
  const Scene scene = make_demo_scene();
  LidarModel model = small_model();
  model.range_noise_stddev = 0.03;
  model.seed = 7;
  const auto first = simulate_scan(scene, kCorridorPose, model);
  const auto second = simulate_scan(scene, kCorridorPose, model);
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first, second);
}

TEST(Lidar, DifferentSeedWithNoiseGivesDifferentPoints) {
  const Scene scene = make_demo_scene();
  LidarModel model = small_model();
  model.range_noise_stddev = 0.03;
  model.seed = 7;
  const auto first = simulate_scan(scene, kCorridorPose, model);
  model.seed = 8;
  const auto second = simulate_scan(scene, kCorridorPose, model);
  ASSERT_EQ(first.size(), second.size());  // noise moves points, it does not drop them
  std::size_t differing = 0;
  for (std::size_t i = 0; i < first.size(); ++i) differing += first[i] == second[i] ? 0 : 1;
  EXPECT_GT(differing, first.size() * 9 / 10);
}

TEST(Lidar, ExactPointsLieOnSurfacesWithinRange) {
  const Scene scene = make_demo_scene();
  LidarModel model = small_model();
  model.max_range = 8.0;  // short enough that some beams along the corridor miss
  const auto points = simulate_scan(scene, kCorridorPose, model);
  ASSERT_FALSE(points.empty());
  EXPECT_LE(points.size(), model.beam_count());
  EXPECT_LT(points.size(), model.beam_count());
  for (const Vec3f& p : points) {
    const Vec3d point(p);
    ASSERT_LT(scene.distance_to_nearest_surface(point), 1e-4)
        << "(" << point.x << ", " << point.y << ", " << point.z << ")";
    ASSERT_LE((point - kCorridorPose.position).norm(), model.max_range + 1e-4);
  }
}

TEST(Lidar, BeamsFollowTheModelGeometry) {
  // A single ring at 0 degrees inside a 2 m x 2 m room seen from its centre:
  // the beam at azimuth yaw hits the wall straight ahead at 1 m.
  Scene room;
  room.add_box({{-2, -2, -1}, {-1, 2, 1}});
  room.add_box({{1, -2, -1}, {2, 2, 1}});
  room.add_box({{-1, -2, -1}, {1, -1, 1}});
  room.add_box({{-1, 1, -1}, {1, 2, 1}});
  LidarModel model;
  model.rings = 1;
  model.fov_down_deg = -10;
  model.fov_up_deg = 10;
  model.azimuth_steps = 4;
  const auto points = simulate_scan(room, {{0, 0, 0}, std::numbers::pi / 2}, model);
  ASSERT_EQ(points.size(), 4u);
  EXPECT_NEAR(points[0].x, 0.0f, 1e-6f);
  EXPECT_NEAR(points[0].y, 1.0f, 1e-6f);  // yaw 90 degrees: first beam along +y
  EXPECT_NEAR(points[1].x, -1.0f, 1e-6f);
  EXPECT_NEAR(points[2].y, -1.0f, 1e-6f);
  EXPECT_NEAR(points[3].x, 1.0f, 1e-6f);
  for (const Vec3f& p : points) EXPECT_NEAR(p.z, 0.0f, 1e-6f);
}

TEST(Lidar, NoiseIsGaussianAlongTheBeam) {
  // A floor only, seen from 2 m above with rings pointing down: every beam
  // hits, so the noisy and exact scans pair up beam by beam.
  Scene floor;
  floor.add_box({{-100, -100, -1}, {100, 100, 0}});
  LidarModel model;
  model.rings = 16;
  model.fov_down_deg = -80;
  model.fov_up_deg = -20;
  model.azimuth_steps = 360;
  model.max_range = 50;
  const SensorPose pose{{0, 0, 2}, 0};
  const auto exact = simulate_scan(floor, pose, model);
  model.range_noise_stddev = 0.05;
  const auto noisy = simulate_scan(floor, pose, model);
  ASSERT_EQ(exact.size(), model.beam_count());
  ASSERT_EQ(noisy.size(), exact.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  std::size_t within_one_sigma = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Vec3d origin = pose.position;
    const double error = (Vec3d(noisy[i]) - origin).norm() - (Vec3d(exact[i]) - origin).norm();
    sum += error;
    sum_sq += error * error;
    within_one_sigma += std::abs(error) <= 0.05 ? 1 : 0;
  }
  const double n = double(exact.size());
  const double mean = sum / n;
  const double stddev = std::sqrt(sum_sq / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.004);  // 4 standard errors for n = 5760
  EXPECT_NEAR(stddev, 0.05, 0.005);
  EXPECT_NEAR(double(within_one_sigma) / n, 0.6827, 0.03);
}

TEST(Lidar, EmitNoReturnAddsFarPoints) {
  // A floor only: the rings above the horizon never hit.
  Scene floor;
  floor.add_box({{-100, -100, -1}, {100, 100, 0}});
  LidarModel model = small_model();
  model.max_range = 20;
  const SensorPose pose{{0, 0, 1.5}, 0};
  const auto hits_only = simulate_scan(floor, pose, model);
  ASSERT_FALSE(hits_only.empty());
  ASSERT_LT(hits_only.size(), model.beam_count());

  model.emit_no_return = true;
  model.no_return_range = 60.0;
  const auto with_far = simulate_scan(floor, pose, model);
  EXPECT_EQ(with_far.size(), model.beam_count());
  std::size_t far = 0;
  for (const Vec3f& p : with_far) {
    const double range = (Vec3d(p) - pose.position).norm();
    if (range > model.max_range) {
      EXPECT_NEAR(range, 60.0, 1e-4);
      ++far;
    }
  }
  EXPECT_EQ(far, model.beam_count() - hits_only.size());
}

void expect_rejected(const LidarModel& model, const std::string& field) {
  try {
    model.validate();
    ADD_FAILURE() << "validate() accepted a bad " << field;
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
  }
  // simulate_scan validates too.
  EXPECT_THROW((void)simulate_scan(make_demo_scene(), kCorridorPose, model), std::invalid_argument);
}

TEST(Lidar, ValidateNamesTheBadField) {
  EXPECT_NO_THROW(LidarModel{}.validate());
  LidarModel m;
  m.rings = 0;
  expect_rejected(m, "rings");
  m = {};
  m.azimuth_steps = 0;
  expect_rejected(m, "azimuth_steps");
  m = {};
  m.fov_down_deg = 20;  // above fov_up_deg = 15
  expect_rejected(m, "fov_up_deg");
  m = {};
  m.fov_down_deg = -95;
  expect_rejected(m, "fov_down_deg");
  m = {};
  m.fov_up_deg = NAN;
  expect_rejected(m, "fov_up_deg");
  m = {};
  m.max_range = 0;
  expect_rejected(m, "max_range");
  m = {};
  m.max_range = INFINITY;
  expect_rejected(m, "max_range");
  m = {};
  m.range_noise_stddev = -0.1;
  expect_rejected(m, "range_noise_stddev");
  m = {};
  m.range_noise_stddev = NAN;
  expect_rejected(m, "range_noise_stddev");
  m = {};
  m.emit_no_return = true;
  m.no_return_range = m.max_range;  // must be beyond max_range
  expect_rejected(m, "no_return_range");
}

TEST(Lidar, RejectsNonFinitePose) {
  EXPECT_THROW((void)simulate_scan(make_demo_scene(), {{NAN, 0, 1}, 0}, LidarModel{}),
               std::invalid_argument);
  EXPECT_THROW((void)simulate_scan(make_demo_scene(), {{1, 6, 1}, INFINITY}, LidarModel{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace umbra::sim
