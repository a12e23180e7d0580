#include "umbra/sim/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "gaussian_source.hpp"

namespace umbra::sim {

namespace {

std::string text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

[[noreturn]] void bad_field(const char* field, const std::string& requirement, double value) {
  std::ostringstream out;
  out << "LidarModel::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

}  // namespace

void LidarModel::validate() const {
  if (rings < 1) bad_field("rings", ">= 1", rings);
  if (!(fov_down_deg > -90.0 && fov_down_deg < 90.0)) {
    bad_field("fov_down_deg", "in (-90, 90)", fov_down_deg);
  }
  if (!(fov_up_deg > -90.0 && fov_up_deg < 90.0))
    bad_field("fov_up_deg", "in (-90, 90)", fov_up_deg);
  if (fov_up_deg < fov_down_deg) {
    bad_field("fov_up_deg", ">= fov_down_deg (" + text(fov_down_deg) + ")", fov_up_deg);
  }
  if (azimuth_steps < 1) bad_field("azimuth_steps", ">= 1", azimuth_steps);
  if (!(max_range > 0.0 && std::isfinite(max_range))) {
    bad_field("max_range", "finite and > 0", max_range);
  }
  if (!(range_noise_stddev >= 0.0 && std::isfinite(range_noise_stddev))) {
    bad_field("range_noise_stddev", "finite and >= 0", range_noise_stddev);
  }
  if (emit_no_return && !(no_return_range > max_range && std::isfinite(no_return_range))) {
    bad_field("no_return_range",
              "finite and > max_range (" + text(max_range) + ") when emit_no_return is set",
              no_return_range);
  }
}

std::size_t LidarModel::beam_count() const {
  return static_cast<std::size_t>(std::max(rings, 0)) *
         static_cast<std::size_t>(std::max(azimuth_steps, 0));
}

std::vector<Vec3f> simulate_scan(const Scene& scene, const SensorPose& pose,
                                 const LidarModel& model) {
  std::vector<Vec3f> points;
  simulate_scan(scene, pose, model, points);
  return points;
}

void simulate_scan(const Scene& scene, const SensorPose& pose, const LidarModel& model,
                   std::vector<Vec3f>& points) {
  model.validate();
  if (!pose.position.is_finite() || !std::isfinite(pose.yaw)) {
    std::ostringstream out;
    out << "simulate_scan: the pose must be finite, got position (" << pose.position.x << ", "
        << pose.position.y << ", " << pose.position.z << ") yaw " << pose.yaw;
    throw std::invalid_argument(out.str());
  }
  points.clear();
  points.reserve(model.beam_count());

  constexpr double degrees = std::numbers::pi / 180.0;
  const double elevation_step =
      model.rings > 1 ? (model.fov_up_deg - model.fov_down_deg) / (model.rings - 1) : 0.0;
  const double first_elevation =
      model.rings > 1 ? model.fov_down_deg : 0.5 * (model.fov_down_deg + model.fov_up_deg);
  const double azimuth_step = 2.0 * std::numbers::pi / model.azimuth_steps;
  detail::GaussianSource noise(model.seed);
  const bool noisy = model.range_noise_stddev > 0.0;

  for (int ring = 0; ring < model.rings; ++ring) {
    const double elevation = (first_elevation + ring * elevation_step) * degrees;
    const double horizontal = std::cos(elevation);
    const double vertical = std::sin(elevation);
    for (int step = 0; step < model.azimuth_steps; ++step) {
      const double azimuth = pose.yaw + step * azimuth_step;
      const Vec3d direction{horizontal * std::cos(azimuth), horizontal * std::sin(azimuth),
                            vertical};
      const auto hit = scene.intersect_unchecked(pose.position, direction, model.max_range);
      double range = 0.0;
      if (hit) {
        range = *hit;
        if (noisy) {
          range = std::clamp(range + model.range_noise_stddev * noise.next(), 0.0, model.max_range);
        }
      } else if (model.emit_no_return) {
        range = model.no_return_range;
      } else {
        continue;
      }
      points.push_back(Vec3f(pose.position + direction * range));
    }
  }
}

}  // namespace umbra::sim
