// Tests of the simulated depth camera: its pinhole geometry against the
// frustum of docs/design.md, Semantics (computed here independently), exact points on the
// surfaces it sees, the range limits, Gaussian noise along the ray with the
// configured spread, determinism from the seed, and its demo trajectory.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::sim {
namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;

/// A wall x in [distance, distance + 1] filling the view of a camera at the origin looking along +x.
Scene wall_at(double distance) {
  Scene scene;
  scene.add_box({{distance, -100, -100}, {distance + 1, 100, 100}});
  return scene;
}

DepthCameraModel small_camera() {
  DepthCameraModel model;
  model.width = 64;
  model.height = 24;
  return model;
}

/// Horizontal and vertical angle of direction d seen from a pose, as docs/design.md
/// (Semantics) defines the information-gain frustum (forward f, left l, up u = f x l).
std::pair<double, double> frustum_angles(const CameraPose& pose, Vec3d d) {
  const Vec3d f{std::cos(pose.pitch) * std::cos(pose.yaw), std::cos(pose.pitch) * std::sin(pose.yaw),
                std::sin(pose.pitch)};
  const Vec3d l{-std::sin(pose.yaw), std::cos(pose.yaw), 0.0};
  const Vec3d u{f.y * l.z - f.z * l.y, f.z * l.x - f.x * l.z, f.x * l.y - f.y * l.x};
  return {std::atan2(d.dot(l), d.dot(f)), std::atan2(d.dot(u), d.dot(f))};
}

TEST(DepthCamera, PixelRaysSpanTheFieldOfViewOfTheFrustum) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (const auto& [hfov, vfov] : {std::pair{115.0, 60.0}, std::pair{58.0, 45.0}, std::pair{90.0, 90.0}}) {
    DepthCameraModel model;
    model.width = 40;
    model.height = 30;
    model.hfov_deg = hfov;
    model.vfov_deg = vfov;
    for (int trial = 0; trial < 5; ++trial) {
      const CameraPose pose{{0, 0, 0}, angle(rng), 0.4 * angle(rng)};
      double widest = 0.0;
      double tallest = 0.0;
      for (int v = 0; v < model.height; ++v) {
        for (int u = 0; u < model.width; ++u) {
          const Vec3d d = model.pixel_direction(pose, u, v);
          ASSERT_NEAR(d.norm(), 1.0, 1e-12);
          const auto [horizontal, vertical] = frustum_angles(pose, d);
          // u grows to the right (negative horizontal angle), v downwards.
          EXPECT_EQ(horizontal > 0.0, u < model.width / 2);
          EXPECT_EQ(vertical > 0.0, v < model.height / 2);
          widest = std::max(widest, std::abs(horizontal));
          tallest = std::max(tallest, std::abs(vertical));
        }
      }
      // Pixel centres lie inside the field of view, the outermost half a pixel from its edge.
      EXPECT_LT(widest, 0.5 * hfov * kDegrees);
      EXPECT_GT(widest, 0.5 * hfov * kDegrees * (1.0 - 2.0 / model.width));
      EXPECT_LT(tallest, 0.5 * vfov * kDegrees);
      EXPECT_GT(tallest, 0.5 * vfov * kDegrees * (1.0 - 2.0 / model.height));
    }
  }
}

TEST(DepthCamera, ExactPointsLieOnTheWallAlongTheirPixelRays) {
  const DepthCameraModel model = small_camera();
  const CameraPose pose{{0, 0, 0}, 0.0, 0.0};
  const std::vector<Vec3f> points = simulate_depth_image(wall_at(2.0), pose, model);
  ASSERT_EQ(points.size(), model.pixel_count());  // every ray is within 6.5 m of the wall: 2 / cos(57.5) = 3.7
  for (int v = 0; v < model.height; ++v) {
    for (int u = 0; u < model.width; ++u) {
      const Vec3d p(points[static_cast<std::size_t>(v * model.width + u)]);
      EXPECT_NEAR(p.x, 2.0, 1e-6);
      const Vec3d d = model.pixel_direction(pose, u, v);
      EXPECT_NEAR((p / p.norm()).dot(d), 1.0, 1e-9) << "pixel " << u << "," << v;
    }
  }
}

TEST(DepthCamera, RangeLimitsAndFarPoints) {
  DepthCameraModel model = small_camera();
  const CameraPose pose{{0, 0, 0}, 0.0, 0.0};
  EXPECT_TRUE(simulate_depth_image(wall_at(6.6), pose, model).empty()) << "beyond max_range";
  model.max_range = 10.0;
  // Range grows towards the image's edges: 6.6 / cos of each ray's angle off the axis.
  std::size_t expected = 0;
  for (int v = 0; v < model.height; ++v) {
    for (int u = 0; u < model.width; ++u) expected += 6.6 / model.pixel_direction(pose, u, v).x <= 10.0;
  }
  EXPECT_EQ(simulate_depth_image(wall_at(6.6), pose, model).size(), expected);
  EXPECT_LT(expected, model.pixel_count());
  model.min_range = 1.0;  // the image's corners see a wall 0.3 m ahead at 0.59 m
  EXPECT_TRUE(simulate_depth_image(wall_at(0.3), pose, model).empty()) << "nearer than min_range";

  model.emit_no_return = true;
  model.no_return_range = 50.0;
  const std::vector<Vec3f> far = simulate_depth_image(wall_at(6.6), pose, model);
  ASSERT_EQ(far.size(), model.pixel_count());
  std::size_t at_no_return = 0;
  for (const Vec3f& p : far) at_no_return += std::abs(Vec3d(p).norm() - 50.0) < 1e-4;
  EXPECT_EQ(at_no_return, model.pixel_count() - expected);
}

TEST(DepthCamera, NoiseIsGaussianAlongTheRayAndGrowsWithTheSquareOfTheRange) {
  DepthCameraModel model;
  model.width = 120;
  model.height = 100;
  model.hfov_deg = 20.0;  // a narrow view: ranges stay close to the wall's distance
  model.vfov_deg = 20.0;
  const CameraPose pose{{0, 0, 0}, 0.0, 0.0};
  for (const double distance : {1.0, 4.0}) {
    const Scene scene = wall_at(distance);
    const std::vector<Vec3f> exact = simulate_depth_image(scene, pose, model);
    DepthCameraModel noisy_model = model;
    noisy_model.noise_stddev = 0.01;
    noisy_model.noise_per_square_metre = 0.002;
    const std::vector<Vec3f> noisy = simulate_depth_image(scene, pose, noisy_model);
    ASSERT_EQ(exact.size(), model.pixel_count());
    ASSERT_EQ(noisy.size(), exact.size());
    double sum = 0.0;
    double sum_sq = 0.0;
    double expected_variance = 0.0;
    for (std::size_t i = 0; i < exact.size(); ++i) {
      const double range = Vec3d(exact[i]).norm();
      const double error = Vec3d(noisy[i]).norm() - range;
      // Along the ray: the noisy point stays on the exact point's ray.
      EXPECT_NEAR((Vec3d(noisy[i]) / Vec3d(noisy[i]).norm()).dot(Vec3d(exact[i]) / range), 1.0, 1e-9);
      const double stddev = 0.01 + 0.002 * range * range;
      sum += error;
      sum_sq += error * error;
      expected_variance += stddev * stddev;
    }
    const double n = static_cast<double>(exact.size());
    const double expected = std::sqrt(expected_variance / n);  // 0.012 at 1 m, 0.042 at 4 m
    EXPECT_NEAR(sum / n, 0.0, 4.0 * expected / std::sqrt(n)) << "at " << distance << " m";
    EXPECT_NEAR(std::sqrt(sum_sq / n), expected, 0.05 * expected) << "at " << distance << " m";
  }
}

TEST(DepthCamera, TheSeedDecidesTheNoiseAndEachFrameOfASequenceHasItsOwn) {
  DepthCameraModel model = small_camera();
  model.noise_stddev = 0.02;
  const Scene scene = make_demo_scene();
  const std::vector<CameraPose> path = demo_camera_path();
  EXPECT_EQ(simulate_depth_image(scene, path[0], model), simulate_depth_image(scene, path[0], model));
  DepthCameraModel other = model;
  other.seed = 2;
  EXPECT_NE(simulate_depth_image(scene, path[0], model), simulate_depth_image(scene, path[0], other));

  const std::vector<CameraPose> two(path.begin(), path.begin() + 2);
  const std::vector<DepthFrame> frames = simulate_depth_sequence(scene, two, model);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].points, simulate_depth_image(scene, path[0], model));
  EXPECT_EQ(frames[1].points, simulate_depth_image(scene, path[1], other));  // seed + 1
  EXPECT_EQ(Vec3d(frames[1].origin), Vec3d(Vec3f(path[1].position)));
}

TEST(DepthCamera, DemoPathIsInFreeSpaceAndEveryFrameSeesTheBuilding) {
  const Scene scene = make_demo_scene();
  const std::vector<CameraPose> path = demo_camera_path();
  EXPECT_EQ(path.size(), 16u);
  const DepthCameraModel model = small_camera();
  for (std::size_t i = 0; i < path.size(); ++i) {
    SCOPED_TRACE("pose " + std::to_string(i));
    EXPECT_FALSE(scene.is_inside_solid(path[i].position));
    EXPECT_GE(scene.distance_to_nearest_surface(path[i].position), 0.3);
    // Indoors, most pixels see a surface within 6.5 m.
    EXPECT_GT(simulate_depth_image(scene, path[i], model).size(), model.pixel_count() * 3 / 4);
  }
}

void expect_rejected(const DepthCameraModel& model, const std::string& field) {
  try {
    model.validate();
    ADD_FAILURE() << field << " was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DepthCameraModel::" + field), std::string::npos) << e.what();
  }
}

TEST(DepthCamera, ValidateNamesTheBadField) {
  EXPECT_NO_THROW(DepthCameraModel{}.validate());
  auto with = [](auto change) {
    DepthCameraModel model;
    change(model);
    return model;
  };
  expect_rejected(with([](auto& m) { m.width = 0; }), "width");
  expect_rejected(with([](auto& m) { m.height = -1; }), "height");
  expect_rejected(with([](auto& m) { m.hfov_deg = 180.0; }), "hfov_deg");
  expect_rejected(with([](auto& m) { m.vfov_deg = 0.0; }), "vfov_deg");
  expect_rejected(with([](auto& m) { m.vfov_deg = std::nan(""); }), "vfov_deg");
  expect_rejected(with([](auto& m) { m.min_range = -0.1; }), "min_range");
  expect_rejected(with([](auto& m) { m.max_range = 0.05; }), "max_range");
  expect_rejected(with([](auto& m) { m.noise_stddev = -1.0; }), "noise_stddev");
  expect_rejected(with([](auto& m) { m.noise_per_square_metre = INFINITY; }), "noise_per_square_metre");
  expect_rejected(with([](auto& m) {
                    m.emit_no_return = true;
                    m.no_return_range = 6.0;
                  }),
                  "no_return_range");
  EXPECT_THROW(simulate_depth_image(wall_at(1.0), CameraPose{{0, 0, std::nan("")}, 0.0, 0.0}, DepthCameraModel{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace umbra::sim
