// umbra_explore_clearance_benchmark: the explorer's ball and capsule checks
// answered by the map (is_free) and by FieldClearance (field_clearance.hpp),
// CPU time per check, and the field's update time per frame.
//
//   build-bench/bench/explore/umbra_explore_clearance_benchmark
//
// The map: the plant of the study (seed 1) seen from the start in 16 frames
// of the study's camera (160 x 84), the field (max distance 1 m) updated
// after each. The checks: 20,000 planner-like ones (radius 0.4 m, a node
// up to 1.5 m from a point within 3 m of the start, and its edge), the same
// list for both; their answers must agree (the program fails otherwise).
// docs/exploration.md reports a run.
#include <cstdio>
#include <ctime>
#include <numbers>
#include <random>
#include <vector>

#include "field_clearance.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/industrial_scene.hpp"
#include "umbra_exploration_map.hpp"

using namespace umbra;
using namespace umbra::explore;

namespace {
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
double uniform(std::mt19937& rng, double low, double high) {
  return low + (high - low) * (double(rng()) / 4294967296.0);
}
/// CPU microseconds per check of `check` over `shapes`, and how many were free.
template <typename Shape, typename Check>
double time_checks(const std::vector<Shape>& shapes, Check check, int& free) {
  free = 0;
  const double start = cpu_seconds();
  for (const Shape& shape : shapes) free += check(shape) ? 1 : 0;
  return (cpu_seconds() - start) / double(shapes.size()) * 1e6;
}
}  // namespace

int main() {
  const sim::IndustrialPlant plant = sim::make_industrial_scene(1);
  UmbraMapOptions options;
  options.clearance = ClearanceSource::distance_field;
  UmbraExplorationMap map(options);
  map.assume_free(Sphere{plant.start, 1.0});
  sim::DepthCameraModel camera;
  camera.width = 160;
  camera.height = 84;
  camera.emit_no_return = true;
  camera.no_return_range = camera.max_range + 1.0;
  std::vector<Vec3f> points;
  constexpr int kFrames = 16;
  for (int k = 0; k < kFrames; ++k) {
    sim::simulate_depth_image(plant.scene, {plant.start, 2.0 * std::numbers::pi * k / kFrames, 0.0}, camera, points);
    map.insert(Vec3f(plant.start), points, camera.max_range);
  }
  std::printf("field update: %.3f CPU s over %d frames (%.1f ms a frame)\n", map.field_update_seconds(), kFrames,
              1e3 * map.field_update_seconds() / kFrames);

  std::mt19937 rng(1);
  std::vector<Sphere> balls;
  std::vector<Capsule> capsules;
  for (int i = 0; i < 20000; ++i) {
    const Vec3d from = plant.start + Vec3d{uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -1, 1)};
    Vec3d step{uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -0.3, 0.3)};
    step = step * (uniform(rng, 0.2, 1.5) / step.norm());
    balls.push_back({from + step, 0.4});
    capsules.push_back({from, from + step, 0.4});
  }
  const FieldClearance& field = *map.field_clearance();
  for (int repeat = 0; repeat < 3; ++repeat) {
    int map_balls = 0, field_balls = 0, map_capsules = 0, field_capsules = 0;
    const double ball_map = time_checks(balls, [&](const Sphere& s) { return map.map().is_free(s).free; }, map_balls);
    const double ball_field = time_checks(balls, [&](const Sphere& s) { return field.is_free(s); }, field_balls);
    const double capsule_map =
        time_checks(capsules, [&](const Capsule& c) { return map.map().is_free(c).free; }, map_capsules);
    const double capsule_field = time_checks(capsules, [&](const Capsule& c) { return field.is_free(c); }, field_capsules);
    if (map_balls != field_balls || map_capsules != field_capsules) {
      std::printf("the answers differ\n");
      return 1;
    }
    std::printf("ball: map %.2f us, field %.2f us (%d free)   capsule: map %.2f us, field %.2f us (%d free)\n", ball_map,
                ball_field, map_balls, capsule_map, capsule_field, map_capsules);
  }
  const ClearanceCounts counts = field.counts();
  std::printf("decided by the field / by the map: balls %llu / %llu, capsules %llu / %llu\n",
              static_cast<unsigned long long>(counts.balls_by_field), static_cast<unsigned long long>(counts.balls_by_map),
              static_cast<unsigned long long>(counts.capsules_by_field), static_cast<unsigned long long>(counts.capsules_by_map));
  return 0;
}
