#include "umbra/sim/depth_camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "gaussian_source.hpp"

namespace umbra::sim {

namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;

[[noreturn]] void bad_field(const char* field, const std::string& requirement, double value) {
  std::ostringstream out;
  out << "DepthCameraModel::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

/// The camera's axes for a pose (see the header): forward, left, up.
struct CameraFrame {
  Vec3d forward;
  Vec3d left;
  Vec3d up;
  explicit CameraFrame(const CameraPose& pose)
      : forward{std::cos(pose.pitch) * std::cos(pose.yaw), std::cos(pose.pitch) * std::sin(pose.yaw),
                std::sin(pose.pitch)},
        left{-std::sin(pose.yaw), std::cos(pose.yaw), 0.0},
        up{forward.y * left.z - forward.z * left.y, forward.z * left.x - forward.x * left.z,
           forward.x * left.y - forward.y * left.x} {}
};

/// Pinhole focal lengths in pixels.
double focal(int pixels, double fov_deg) { return 0.5 * pixels / std::tan(0.5 * fov_deg * kDegrees); }

Vec3d direction(const CameraFrame& frame, double fx, double fy, const DepthCameraModel& model, int u, int v) {
  const double right = (u + 0.5 - 0.5 * model.width) / fx;
  const double down = (v + 0.5 - 0.5 * model.height) / fy;
  const Vec3d d = frame.forward - frame.left * right - frame.up * down;
  return d / d.norm();
}

}  // namespace

void DepthCameraModel::validate() const {
  if (width < 1) bad_field("width", ">= 1", width);
  if (height < 1) bad_field("height", ">= 1", height);
  if (!(hfov_deg > 0.0 && hfov_deg < 180.0)) bad_field("hfov_deg", "in (0, 180)", hfov_deg);
  if (!(vfov_deg > 0.0 && vfov_deg < 180.0)) bad_field("vfov_deg", "in (0, 180)", vfov_deg);
  if (!(min_range >= 0.0 && std::isfinite(min_range))) bad_field("min_range", "finite and >= 0", min_range);
  if (!(max_range > min_range && std::isfinite(max_range))) {
    bad_field("max_range", "finite and > min_range", max_range);
  }
  if (!(noise_stddev >= 0.0 && std::isfinite(noise_stddev))) {
    bad_field("noise_stddev", "finite and >= 0", noise_stddev);
  }
  if (!(noise_per_square_metre >= 0.0 && std::isfinite(noise_per_square_metre))) {
    bad_field("noise_per_square_metre", "finite and >= 0", noise_per_square_metre);
  }
  if (emit_no_return && !(no_return_range > max_range && std::isfinite(no_return_range))) {
    bad_field("no_return_range", "finite and > max_range when emit_no_return is set", no_return_range);
  }
}

std::size_t DepthCameraModel::pixel_count() const {
  return static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0));
}

Vec3d DepthCameraModel::pixel_direction(const CameraPose& pose, int u, int v) const {
  return direction(CameraFrame(pose), focal(width, hfov_deg), focal(height, vfov_deg), *this, u, v);
}

std::vector<Vec3f> simulate_depth_image(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model) {
  std::vector<Vec3f> points;
  simulate_depth_image(scene, pose, model, points);
  return points;
}

namespace {

/// Calls visit(u, v, direction, range) for every pixel that gives a point
/// (see the header), row by row from the top.
template <typename Visit>
void for_each_reading(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model, Visit&& visit) {
  model.validate();
  if (!pose.position.is_finite() || !std::isfinite(pose.yaw) || !std::isfinite(pose.pitch)) {
    std::ostringstream out;
    out << "simulate_depth_image: the pose must be finite, got position (" << pose.position.x << ", "
        << pose.position.y << ", " << pose.position.z << ") yaw " << pose.yaw << " pitch " << pose.pitch;
    throw std::invalid_argument(out.str());
  }
  const CameraFrame frame(pose);
  const double fx = focal(model.width, model.hfov_deg);
  const double fy = focal(model.height, model.vfov_deg);
  detail::GaussianSource noise(model.seed);
  const bool noisy = model.noise_stddev > 0.0 || model.noise_per_square_metre > 0.0;
  for (int v = 0; v < model.height; ++v) {
    for (int u = 0; u < model.width; ++u) {
      const Vec3d d = direction(frame, fx, fy, model, u, v);
      const auto hit = scene.intersect_unchecked(pose.position, d, model.max_range);
      double range = 0.0;
      if (hit && *hit >= model.min_range) {
        range = *hit;
        if (noisy) {
          const double stddev = model.noise_stddev + model.noise_per_square_metre * range * range;
          range = std::clamp(range + stddev * noise.next(), 0.0, model.max_range);
        }
      } else if (!hit && model.emit_no_return) {
        range = model.no_return_range;
      } else {
        continue;
      }
      visit(u, v, d, range);
    }
  }
}

}  // namespace

void simulate_depth_image(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model,
                          std::vector<Vec3f>& points) {
  points.clear();
  points.reserve(model.pixel_count());
  for_each_reading(scene, pose, model,
                   [&](int, int, Vec3d d, double range) { points.push_back(Vec3f(pose.position + d * range)); });
}

DepthImage SimulatedDepthImage::view() const { return DepthImage::metres(depth, width, height); }

SimulatedDepthImage simulate_depth_frame(const Scene& scene, const CameraPose& pose, const DepthCameraModel& model) {
  SimulatedDepthImage image;
  image.width = model.width;
  image.height = model.height;
  image.depth.assign(model.pixel_count(), 0.0f);
  const CameraFrame frame(pose);
  const double fx = focal(model.width, model.hfov_deg);
  const double fy = focal(model.height, model.vfov_deg);
  // Pixel (u, v) looks along forward + right (u + 1/2 - width / 2) / fx + down
  // (v + 1/2 - height / 2) / fy: a pinhole with its principal point there and
  // the optical axes right = -left, down = -up, forward.
  image.camera = PinholeCamera{fx, fy, 0.5 * model.width - 0.5, 0.5 * model.height - 0.5};
  const Vec3d right = frame.left * -1.0;
  const Vec3d down = frame.up * -1.0;
  image.pose.m = {{{right.x, down.x, frame.forward.x, pose.position.x},
                   {right.y, down.y, frame.forward.y, pose.position.y},
                   {right.z, down.z, frame.forward.z, pose.position.z}}};
  for_each_reading(scene, pose, model, [&](int u, int v, Vec3d d, double range) {
    image.depth[static_cast<std::size_t>(v) * static_cast<std::size_t>(model.width) + static_cast<std::size_t>(u)] =
        static_cast<float>(range * d.dot(frame.forward));
  });
  return image;
}

std::vector<SimulatedDepthImage> simulate_depth_frames(const Scene& scene, std::span<const CameraPose> poses,
                                                       const DepthCameraModel& model) {
  std::vector<SimulatedDepthImage> frames;
  frames.reserve(poses.size());
  DepthCameraModel per_frame = model;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    per_frame.seed = model.seed + static_cast<std::uint32_t>(i);
    frames.push_back(simulate_depth_frame(scene, poses[i], per_frame));
  }
  return frames;
}

std::vector<DepthFrame> simulate_depth_sequence(const Scene& scene, std::span<const CameraPose> poses,
                                                const DepthCameraModel& model) {
  std::vector<DepthFrame> frames(poses.size());
  DepthCameraModel per_frame = model;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    per_frame.seed = model.seed + static_cast<std::uint32_t>(i);
    frames[i].origin = Vec3f(poses[i].position);
    simulate_depth_image(scene, poses[i], per_frame, frames[i].points);
  }
  return frames;
}

std::vector<CameraPose> demo_camera_path() {
  constexpr double height = 1.3;
  constexpr double down = -0.15;  // radians, looking slightly down
  constexpr double east = 0.0;
  constexpr double north = std::numbers::pi / 2;
  constexpr double pan = 0.5;  // radians to either side
  // clang-format off
  return {
      {{1.0, 6.0, height}, east, down},          // west end of the corridor
      {{1.4, 6.0, height}, east + pan, down},    // panning into the rooms on either side
      {{1.8, 6.0, height}, east - pan, down},
      {{2.2, 6.0, height}, east, down},
      {{2.7, 6.0, height}, east + pan, down},
      {{3.2, 6.0, height}, east - pan, down},
      {{3.7, 6.0, height}, east, down},
      {{4.2, 6.0, height}, east + pan, down},
      {{4.7, 6.0, height}, east - pan, down},
      {{5.2, 6.0, height}, east, down},
      {{9.4, 6.0, height}, north / 2, down},     // turning towards the meeting-room door
      {{9.8, 6.4, height}, north, down},
      {{10.0, 6.8, height}, north, down},        // in the doorway
      {{10.0, 7.6, height}, north + pan, down},  // inside, looking around
      {{10.0, 7.8, height}, north - pan, down},
      {{10.2, 8.0, height}, north, 2 * down},
  };
  // clang-format on
}

DepthCameraModel noisy_depth_camera(std::uint32_t seed) {
  DepthCameraModel model;
  model.noise_stddev = 0.002;
  model.noise_per_square_metre = 0.0015;
  model.seed = seed;
  return model;
}

std::vector<DepthFrame> demo_depth_sequence(std::uint32_t seed) {
  return simulate_depth_sequence(make_demo_scene(), demo_camera_path(), noisy_depth_camera(seed));
}

std::vector<SimulatedDepthImage> demo_depth_images(std::uint32_t seed) {
  const std::vector<CameraPose> path = demo_camera_path();
  return simulate_depth_frames(make_demo_scene(), path, noisy_depth_camera(seed));
}

}  // namespace umbra::sim
