// Uses the installed headers and libraries: core (a scan, a query) and io (a file).
#include <cstdio>
#include <filesystem>
#include <vector>

#include <umbra/io/map_file.hpp>
#include <umbra/map/occupancy_map.hpp>

int main(int argc, char** argv) {
  umbra::OccupancyMap map(0.1);
  const std::vector<umbra::Vec3f> points = {{1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
  map.insert_point_cloud({0.0f, 0.0f, 0.0f}, points);
  if (map.state({1.0, 0.0, 0.0}) != umbra::OccupancyState::occupied) return 1;
  const std::filesystem::path path = argc > 1 ? argv[1] : "consumer.umb";
  umbra::save_map(map, path);
  const umbra::OccupancyMap loaded = umbra::load_map(path);
  std::printf("consumer ok: %zu nodes\n", loaded.node_counts().total());
  return loaded.state({0.0, 1.0, 0.0}) == umbra::OccupancyState::occupied ? 0 : 1;
}
