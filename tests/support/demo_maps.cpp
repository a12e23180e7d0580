#include "support/demo_maps.hpp"

#include <stdexcept>
#include <vector>

#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::test {

OccupancyMap demo_lidar_map(const MapConfig& config, const PointColor& color) {
  if (config.color && !color) throw std::invalid_argument("demo_lidar_map: a colored map needs a color function");
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  OccupancyMap map(config);
  InsertOptions insert;
  insert.max_range = lidar.max_range;
  std::vector<Vec3f> points;
  std::vector<Rgb> colors;
  for (const sim::SensorPose& pose : sim::demo_path()) {
    sim::simulate_scan(scene, pose, lidar, points);
    if (config.color) {
      colors.clear();
      for (std::size_t i = 0; i < points.size(); ++i) colors.push_back(color(i, points[i]));
      map.insert_point_cloud(Vec3f(pose.position), points, colors, insert);
    } else {
      map.insert_point_cloud(Vec3f(pose.position), points, insert);
    }
  }
  return map;
}

std::vector<Scan> lidar_building_scans() {
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  lidar.range_noise_stddev = 0.01;
  std::vector<Scan> scans;
  const auto path = sim::demo_path();
  for (std::size_t i = 0; i < path.size(); i += 2) {
    Scan scan;
    scan.origin = static_cast<Vec3f>(path[i].position);
    scan.points = sim::simulate_scan(scene, path[i], lidar);
    scans.push_back(std::move(scan));
  }
  return scans;
}

}  // namespace umbra::test
