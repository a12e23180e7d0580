// A distance field of the simulated office, and a picture of it: the
// horizontal slice at 1.2 m colored by the distance to the nearest
// blocking voxel (occupied black, unknown grey, free space from dark blue
// near an obstacle to yellow at 1 m or more).
//
//   build/examples/example_distance_field_slice [out.png]
#include <algorithm>
#include <cstdio>
#include <vector>

#include <umbra/io/png_writer.hpp>
#include <umbra/map/occupancy_map.hpp>
#include <umbra/field/distance_field.hpp>
#include <umbra/sim/lidar.hpp>
#include <umbra/sim/scene.hpp>

int main(int argc, char** argv) {
  umbra::OccupancyMap map(0.05);
  const umbra::sim::Scene office = umbra::sim::make_demo_scene();
  for (const umbra::sim::SensorPose& pose : umbra::sim::demo_path()) {
    const std::vector<umbra::Vec3f> points = umbra::sim::simulate_scan(office, pose, {});
    map.insert_point_cloud(umbra::Vec3f(pose.position), points);
  }
  // Built once here; after further scans, field.update() recomputes only
  // near what they changed.
  umbra::DistanceFieldOptions options;
  options.max_distance = 1.0;
  options.threads = 0;  // all cores
  const umbra::DistanceField field(map, options);
  std::printf("field of %zu bricks, %.1f MB\n", field.stats().bricks, double(field.memory_bytes()) / 1e6);

  // The slice: one pixel per voxel over x in [-1, 21), y in [-1, 13), all asked in one batch.
  const int width = 440, height = 280;
  std::vector<umbra::Vec3d> points;
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      points.push_back({-1.0 + (column + 0.5) * 0.05, 13.0 - (row + 0.5) * 0.05, 1.2});
    }
  }
  std::vector<umbra::DistanceSample> samples(points.size());
  field.distance_and_gradient(points, samples);
  umbra::Image image(width, height);
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      const umbra::DistanceSample& s = samples[std::size_t(row) * width + column];
      umbra::Rgb color{128, 128, 128};  // unknown
      if (s.occupied == 0.0) {
        color = {0, 0, 0};
      } else if (s.unknown > 0.0) {
        const double t = std::min(1.0, s.blocking() / options.max_distance);
        color = {std::uint8_t(40 + 215 * t), std::uint8_t(30 + 200 * t), std::uint8_t(140 * (1 - t))};
      }
      image.set(column, row, color);
    }
  }
  const char* path = argc > 1 ? argv[1] : "distance_field_slice.png";
  umbra::write_png(image, path);
  std::printf("wrote %s\n", path);
  return 0;
}
