// `umbra demo [-o DIR]`: a map of a built-in building seen by a simulated
// LiDAR, written as DIR/demo.umb and DIR/demo.png. Needs no data at all.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "report.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/io/topdown_image.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::cli {
namespace {

struct DemoOptions {
  std::string output_dir = "demo-output";
  double resolution = 0.05;
};

int run_demo(const DemoOptions& options) {
  const std::filesystem::path dir = options.output_dir;
  std::filesystem::create_directories(dir);

  const sim::Scene scene = sim::make_demo_scene();
  const std::vector<sim::SensorPose> path = sim::demo_path();
  sim::LidarModel lidar;
  lidar.range_noise_stddev = 0.01;

  OccupancyMap map(options.resolution);
  InsertOptions insert;
  insert.max_range = lidar.max_range;
  std::printf("umbra demo: a simulated %d-ring LiDAR walks %zu poses through a built-in building, %g m voxels\n",
              lidar.rings, path.size(), options.resolution);
  double insert_seconds = 0.0;
  std::size_t points = 0;
  std::vector<Vec3f> scan;
  for (std::size_t i = 0; i < path.size(); ++i) {
    sim::simulate_scan(scene, path[i], lidar, scan);
    const auto start = std::chrono::steady_clock::now();
    const InsertStats stats = map.insert_point_cloud(static_cast<Vec3f>(path[i].position), scan, insert);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    insert_seconds += seconds;
    points += stats.points;
    std::printf("  scan %2zu at (%5.2f, %5.2f, %4.2f): %6zu points, %6.1f ms\n", i + 1, path[i].position.x,
                path[i].position.y, path[i].position.z, stats.points, seconds * 1e3);
  }
  std::printf("inserted %zu points in %.3f s (%.2f M points/s)\n", points, insert_seconds,
              static_cast<double>(points) / insert_seconds / 1e6);
  print_statistics(stdout, compute_statistics(map));

  const std::filesystem::path map_path = dir / "demo.umb";
  save_map(map, map_path);
  TopdownOptions picture;
  picture.min_z = 0.15;  // above the floor and
  picture.max_z = 2.78;  // below the 3 m ceiling, so walls and furniture show
  const std::filesystem::path image_path = dir / "demo.png";
  write_png(render_topdown(map, picture), image_path);
  std::printf("wrote %s and %s\n", map_path.c_str(), image_path.c_str());
  return 0;
}

}  // namespace

Command add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand("demo", "Map a built-in building with a simulated LiDAR (no data needed)");
  command->add_option("-o,--output-dir", options->output_dir, "folder for demo.umb and demo.png")->capture_default_str();
  command->add_option("--res", options->resolution, "voxel edge in metres")->capture_default_str()->check(CLI::PositiveNumber);
  return [options] { return run_demo(*options); };
}

}  // namespace umbra::cli
