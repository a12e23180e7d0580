// Insert one scan, ask the map questions, save it.
//
//   build/examples/example_insert_and_query [out.umb]
#include <cmath>
#include <cstdio>
#include <vector>

#include <umbra/io/map_file.hpp>
#include <umbra/map/occupancy_map.hpp>

int main(int argc, char** argv) {
  // A 10 cm map with OctoMap's default sensor model and 16 depth levels.
  umbra::OccupancyMap map(0.1);

  // A sensor at 1 m height sees a circular wall of radius 4 m.
  const umbra::Vec3f origin{0.0f, 0.0f, 1.0f};
  std::vector<umbra::Vec3f> points;
  for (int i = 0; i < 720; ++i) {
    for (int h = 0; h < 10; ++h) {
      const double angle = i * M_PI / 360.0;
      points.push_back({static_cast<float>(4.0 * std::cos(angle)), static_cast<float>(4.0 * std::sin(angle)),
                        0.2f * static_cast<float>(h)});
    }
  }
  umbra::InsertOptions options;
  options.integrator = umbra::IntegratorKind::discrete;
  const umbra::InsertStats stats = map.insert_point_cloud(origin, points, options);
  std::printf("%zu points, %zu rays, %zu hits\n", stats.points, stats.rays, stats.hits);

  // Finest voxels.
  std::printf("(4, 0, 1) is %s\n", umbra::to_string(map.state({4.0, 0.0, 1.0})));
  std::printf("(2, 0, 1) is %s\n", umbra::to_string(map.state({2.0, 0.0, 1.0})));
  std::printf("(9, 9, 9) is %s\n", umbra::to_string(map.state({9.0, 9.0, 9.0})));
  // Coarser questions: is the 80 cm block around (2, 0, 1) obstacle-free and fully known?
  const umbra::Vec3d block{2.0, 0.0, 1.0};
  std::printf("80 cm block: occupied inside %d, unknown inside %d\n", map.contains_occupied(block, 3),
              map.contains_unknown(block, 3));

  const char* path = argc > 1 ? argv[1] : "example.umb";
  umbra::save_map(map, path);
  std::printf("saved %s (%zu bytes of map in memory)\n", path, map.memory_bytes());
  return 0;
}
