// `umbra demo [-o DIR]`: a map of a built-in building seen by a simulated
// LiDAR, written as DIR/demo.umb and DIR/demo.png. Needs no data at all.
// `umbra demo --moving`: the same building with a person walking and a door
// opening, mapped with decay toward unknown; the map at three moments as
// DIR/moving-tSS.umb and a slice through it, DIR/moving-tSS.png.
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
#include "umbra/io/map_render.hpp"
#include "umbra/map/decay.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/moving_scene.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::cli {
namespace {

struct DemoOptions {
  std::string output_dir = "demo-output";
  double resolution = 0.05;
  bool moving = false;
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

/// Where the demo path's sensor is at `time`: pose i at i seconds, in a
/// straight line (and turn) between them, and the last pose from then on.
sim::CameraPose demo_camera_at(const std::vector<sim::SensorPose>& path, double time) {
  const double last = static_cast<double>(path.size() - 1);
  if (time >= last) return {path.back().position, path.back().yaw, 0.0};
  const auto i = static_cast<std::size_t>(time);
  const double f = time - static_cast<double>(i);
  return {path[i].position + (path[i + 1].position - path[i].position) * f,
          path[i].yaw + (path[i + 1].yaw - path[i].yaw) * f, 0.0};
}

/// The moving demo: a person walks along the corridor and a door slides open
/// (sim::make_demo_moving_scene) while a depth camera goes down the corridor
/// and into the meeting room in 9 s (sim::demo_path, one pose a second) and
/// stays there until 14 s; images at 10 Hz, stamped, into a map that forgets
/// 1.0 log-odds a second of occupancy and 0.5 of freedom (a wall at the 3.5
/// clamp is unknown 3.5 s after it was last seen, free space at -2 after
/// 4 s). The slices at the camera's height show the person's trail seen
/// free again, the door open, and the corridor left behind faded to unknown.
int run_moving_demo(const DemoOptions& options) {
  const std::filesystem::path dir = options.output_dir;
  std::filesystem::create_directories(dir);
  const sim::MovingScene scene = sim::make_demo_moving_scene();
  const std::vector<sim::SensorPose> path = sim::demo_path();
  sim::DepthCameraModel camera;
  camera.width = 320;
  camera.height = 120;
  camera.max_range = 8.0;
  camera.noise_stddev = 0.005;
  // Pixels that see nothing within 8 m (down the corridor) still clear up
  // to 8 m, as a camera's "no return" does in practice.
  camera.emit_no_return = true;

  OccupancyMap map(options.resolution);
  DecayRates decay;
  decay.occupied_per_second = 1.0;
  decay.free_per_second = 0.5;
  map.set_decay(decay);
  InsertOptions insert;
  insert.integrator = IntegratorKind::projective;
  insert.max_range = camera.max_range;
  std::printf("umbra demo --moving: a person walks and a door opens while a simulated depth camera maps the "
              "building at 10 Hz, %g m voxels, decay %g (occupied) and %g (free) log-odds per second\n",
              options.resolution, decay.occupied_per_second, decay.free_per_second);
  constexpr int kImagesPerSecond = 10;
  constexpr int kMoments[] = {3, 7, 14};  // seconds: the pictures
  const double height = path.front().position.z;
  const sim::Box building = scene.still().bounds();
  int next_moment = 0;
  for (int tick = 0; tick <= kMoments[2] * kImagesPerSecond; ++tick) {
    const double time = static_cast<double>(tick) / kImagesPerSecond;
    const sim::CameraPose pose = demo_camera_at(path, time);
    const sim::SimulatedDepthImage image = sim::simulate_depth_frame(scene.at(time), pose, camera);
    insert.stamp = time;
    (void)map.insert_depth_image(image.view(), image.camera, image.pose, {}, insert);
    if (tick != kMoments[next_moment] * kImagesPerSecond) continue;
    char name[32];
    std::snprintf(name, sizeof name, "moving-t%02d", kMoments[next_moment]);
    save_map(map, dir / (std::string(name) + ".umb"));
    RenderOptions picture;  // as `umbra render MAP --slice z=1.2 --frame` the building
    picture.slice = RenderSlice{2, height};
    picture.view = slice_view(2);
    picture.color = RenderColor::state;
    picture.frame = Aabb{building.min, building.max};
    picture.annotate = true;
    picture.width = 640;
    write_png(render_map(map, picture).image, dir / (std::string(name) + ".png"));
    const MapStatistics stats = compute_statistics(map);
    const Vec3d person = scene.walker_position(0, time);
    const sim::SlidingDoor& door = scene.doors()[0];
    std::printf("  %4.1f s: camera at (%5.2f, %5.2f), person at (%5.2f, %5.2f), door %s; %llu occupied and %llu "
                "free voxels: %s.umb, %s.png\n",
                time, pose.position.x, pose.position.y, person.x, person.y,
                time <= door.open_start ? "closed" : (time >= door.open_end ? "open" : "opening"),
                static_cast<unsigned long long>(stats.occupied_voxels),
                static_cast<unsigned long long>(stats.free_voxels), name, name);
    ++next_moment;
  }
  std::printf("wrote %s/moving-t03, -t07 and -t14 (.umb and .png: slices at z = %g m; red occupied, grey free, "
              "dark unknown)\n", dir.c_str(), height);
  return 0;
}

}  // namespace

Command add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand("demo", "Map a built-in building with a simulated LiDAR (no data needed)");
  command->add_option("-o,--output-dir", options->output_dir, "folder for demo.umb and demo.png")->capture_default_str();
  command->add_option("--res", options->resolution, "voxel edge in metres")->capture_default_str()->check(CLI::PositiveNumber);
  command->add_flag("--moving", options->moving,
                    "a person walks and a door opens; the map decays toward unknown (pictures at three moments)");
  return [options] { return options->moving ? run_moving_demo(*options) : run_demo(*options); };
}

}  // namespace umbra::cli
