// Build a map of the simulated office, then ask it what a planner asks.
//
//   build/examples/example_query_map
#include <cstdio>
#include <vector>

#include <umbra/map/occupancy_map.hpp>
#include <umbra/sim/lidar.hpp>
#include <umbra/sim/scene.hpp>

int main() {
  // A 5 cm map of the demo building, seen by a simulated LiDAR along its corridor.
  umbra::OccupancyMap map(0.05);
  const umbra::sim::Scene office = umbra::sim::make_demo_scene();
  umbra::InsertOptions options;
  options.integrator = umbra::IntegratorKind::discrete;
  for (const umbra::sim::SensorPose& pose : umbra::sim::demo_path()) {
    const std::vector<umbra::Vec3f> points = umbra::sim::simulate_scan(office, pose, {});
    map.insert_point_cloud(umbra::Vec3f(pose.position), points, options);
  }

  // Iterate: the obstacles within 1.5 m of a point (finest voxels and pruned blocks).
  const umbra::Vec3d here{4.0, 6.0, 1.2};
  std::size_t obstacles = 0;
  for (const umbra::Node& node :
       map.query(umbra::pred::leaf() && umbra::pred::occupied() && umbra::pred::intersects(umbra::Sphere{here, 1.5}))) {
    obstacles += node.depth == 0 ? 1 : 0;
  }
  std::printf("occupied voxels within 1.5 m of (4, 6, 1.2): %zu\n", obstacles);

  // Collision checks: unknown space blocks unless the caller says otherwise.
  const umbra::CollisionResult ball = map.is_free(umbra::Sphere{here, 0.3});
  std::printf("a 0.3 m ball at (4, 6, 1.2) is %s\n", ball.free ? "free" : "blocked");
  const umbra::CollisionResult path = map.is_free(umbra::Capsule{here, {10.0, 6.0, 1.2}, 0.3});
  if (path.free) {
    std::printf("a 0.3 m wide path to (10, 6, 1.2) is free\n");
  } else {
    std::printf("the path to (10, 6, 1.2) is blocked at (%.2f, %.2f, %.2f)\n", path.blocking->center.x,
                path.blocking->center.y, path.blocking->center.z);
  }
  // The same check at depth 2 (20 cm nodes): conservative and cheaper.
  std::printf("coarse check at 20 cm: %s\n", map.is_free(umbra::Sphere{here, 0.3}, {.depth = 2}).free ? "free" : "blocked");

  // Ray cast: the first obstacle looking north (unknown space is passed through).
  const umbra::RayHit hit = map.cast_ray(here, {0.0, 1.0, 0.0}, {.max_range = 30.0});
  if (hit.hit) {
    std::printf("north: obstacle at %.2f m\n", hit.distance);
  } else {
    std::printf("north: no obstacle within 30 m\n");
  }

  // Nearest obstacle.
  for (const umbra::NearNode& near :
       map.query_nearest(here, umbra::pred::leaf() && umbra::pred::occupied(), 0, 5.0)) {
    std::printf("nearest obstacle: %.2f m away\n", near.distance);
    break;
  }
  // Unknown space left in the office, in 20 cm nodes.
  std::printf("unknown 20 cm nodes in the building: %zu\n",
              map.count(umbra::pred::leaf() && umbra::pred::unknown() &&
                            umbra::pred::intersects(umbra::Aabb{{0.0, 0.0, 0.0}, {20.0, 12.0, 3.0}}),
                        2));
  return ball.free ? 0 : 1;
}
