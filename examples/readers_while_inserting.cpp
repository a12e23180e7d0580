// One thread inserts scans while another plans on the same map.
//
//   build/examples/example_readers_while_inserting
//
// No lock of the caller's: every query sees the map after some whole scan,
// and inserting keeps queries out only while it applies a traced scan.
#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>

#include <umbra/map/occupancy_map.hpp>
#include <umbra/sim/lidar.hpp>
#include <umbra/sim/scene.hpp>

int main() {
  umbra::OccupancyMap map(0.05);
  map.set_auto_prune(false);  // optional: no node a reader has seen disappears
  const umbra::sim::Scene office = umbra::sim::make_demo_scene();
  std::atomic<bool> mapping{true};

  std::thread planner([&] {
    std::size_t checks = 0;
    std::size_t free = 0;
    while (mapping.load()) {
      // A query at any time, from any thread: no lock needed.
      free += map.is_free(umbra::Sphere{{2.0, 6.0, 1.2}, 0.3}, {.unknown_is_free = false}).free ? 1 : 0;
      ++checks;
    }
    std::printf("planner: %zu checks while mapping, %zu found the ball free\n", checks, free);
  });

  umbra::InsertOptions options;
  options.integrator = umbra::IntegratorKind::fast;
  double closed = 0.0;
  for (const umbra::sim::SensorPose& pose : umbra::sim::demo_path()) {
    const std::vector<umbra::Vec3f> points = umbra::sim::simulate_scan(office, pose, {});
    closed += map.insert_point_cloud(umbra::Vec3f(pose.position), points, options).exclusive_seconds;
  }
  mapping.store(false);
  planner.join();
  std::printf("mapping kept the planner out for %.1f ms in all\n", 1e3 * closed);
  return map.is_free(umbra::Sphere{{2.0, 6.0, 1.2}, 0.3}).free ? 0 : 1;
}
