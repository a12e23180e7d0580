// umbra_count_nodes MAP DEPTH: what the library says `umbra view` should
// draw at a depth, for tests/viewer/viewer_test.mjs. Prints one JSON object:
// for occupied, free and unknown, the count of map.count(pred::leaf() &&
// pred::<state>(), DEPTH) and the nodes' total volume in m^3. Unknown nodes
// are those overlapping the known space's bounding box (MapStatistics), and
// their volume is the part inside it, as the page draws them.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

#include "umbra/io/map_formats.hpp"
#include "umbra/map/map_statistics.hpp"
#include "umbra/query/predicate.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: umbra_count_nodes MAP DEPTH\n");
    return 2;
  }
  try {
    using namespace umbra;
    const OccupancyMap map = load_any_map(argv[1]);
    const int depth = std::stoi(argv[2]);
    const MapStatistics stats = compute_statistics(map);
    std::printf("{\"depth\": %d", depth);
    const char* names[] = {"occupied", "free", "unknown"};
    const Predicate states[] = {pred::occupied(), pred::free(), pred::unknown()};
    for (int i = 0; i < 3; ++i) {
      Predicate predicate = pred::leaf() && states[i];
      if (i == 2) {
        // A box with its faces on voxel centres: it meets a node exactly
        // when the node overlaps the known space by a voxel or more.
        const double half = 0.5 * map.resolution();
        predicate = predicate && pred::intersects(Aabb{stats.known_min + Vec3d{half, half, half},
                                                       stats.known_max - Vec3d{half, half, half}});
      }
      double volume = 0.0;
      if (stats.has_known_space) {
        for (const Node& node : map.query(predicate, depth)) {
          double inside = 1.0;
          for (std::size_t axis = 0; axis < 3; ++axis) {
            inside *= std::min(node.max_corner()[axis], stats.known_max[axis]) -
                      std::max(node.min_corner()[axis], stats.known_min[axis]);
          }
          volume += inside;
        }
      }
      const std::size_t count = stats.has_known_space ? map.count(predicate, depth) : 0;
      std::printf(", \"%s\": {\"count\": %zu, \"volume\": %.9g}", names[i], count, volume);
    }
    std::printf("}\n");
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "umbra_count_nodes: %s\n", error.what());
    return 1;
  }
}
