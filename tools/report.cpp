#include "report.hpp"

#include <array>
#include <cinttypes>
#include <cmath>
#include <ostream>
#include <sstream>

namespace umbra::cli {

std::string human_bytes(std::size_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 4) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, unit == 0 ? "%.0f %s" : "%.1f %s", value, units[unit]);
  return text;
}

void print_statistics(std::FILE* out, const MapStatistics& s) {
  std::fprintf(out, "  resolution        %g m, %d depth levels\n", s.resolution, s.depth_levels);
  std::fprintf(out, "  nodes             %zu (inner %zu, inner leaf %zu, leaf %zu)\n", s.nodes.total(),
               s.nodes.inner, s.nodes.inner_leaf, s.nodes.leaf);
  std::fprintf(out, "  memory            %s (%zu bytes)\n", human_bytes(s.memory_bytes).c_str(), s.memory_bytes);
  std::fprintf(out, "  occupied voxels   %" PRIu64 " (%.4f m^3)\n", s.occupied_voxels, s.occupied_volume_m3);
  std::fprintf(out, "  free voxels       %" PRIu64 " (%.4f m^3)\n", s.free_voxels, s.free_volume_m3);
  if (s.has_known_space) {
    std::fprintf(out, "  known space       min (%.3f, %.3f, %.3f) max (%.3f, %.3f, %.3f) m\n", s.known_min.x,
                 s.known_min.y, s.known_min.z, s.known_max.x, s.known_max.y, s.known_max.z);
  } else {
    std::fprintf(out, "  known space       none (the map is empty)\n");
  }
}

namespace {

/// A JSON number: JSON has no inf or NaN, so those are written as null
/// (resolutions are bounded, so no map of umbra's makes them; this keeps
/// the output valid whatever happens).
struct JsonNumber {
  double value;
  friend std::ostream& operator<<(std::ostream& out, JsonNumber n) {
    return std::isfinite(n.value) ? out << n.value : out << "null";
  }
};

}  // namespace

std::size_t octomap_node_count(const OccupancyMap& map) {
  // In Morton order the ancestors of successive childless nodes share a
  // prefix: each known node adds itself and those ancestors not counted yet,
  // found by comparing with the last ancestor counted at each depth.
  const int levels = map.depth_levels();
  std::array<std::uint64_t, kMaxDepthLevels + 1> last{};
  std::array<bool, kMaxDepthLevels + 1> counted{};
  std::size_t count = 0;
  map.for_each_leaf([&](const Node& node) {
    if (node.log_odds == 0.0f) return;  // never observed: OctoMap has no node there
    ++count;
    const std::uint64_t code = node.code();
    for (int depth = node.depth + 1; depth <= levels; ++depth) {
      const std::uint64_t ancestor = code >> (3 * depth);  // 3 * 21 = 63 bits at most
      if (counted[depth] && last[depth] == ancestor) break;  // it, and so every node above it, is counted
      counted[depth] = true;
      last[depth] = ancestor;
      ++count;
    }
  });
  return count;
}

std::string statistics_json(const MapStatistics& s, const std::string& extra) {
  std::ostringstream json;
  json.precision(17);
  json << "{\"resolution\": " << JsonNumber{s.resolution} << ", \"depth_levels\": " << s.depth_levels
       << ", \"nodes\": " << s.nodes.total() << ", \"inner_nodes\": " << s.nodes.inner
       << ", \"inner_leaf_nodes\": " << s.nodes.inner_leaf << ", \"leaf_nodes\": " << s.nodes.leaf
       << ", \"memory_bytes\": " << s.memory_bytes << ", \"occupied_voxels\": " << s.occupied_voxels
       << ", \"free_voxels\": " << s.free_voxels << ", \"occupied_volume_m3\": " << JsonNumber{s.occupied_volume_m3}
       << ", \"free_volume_m3\": " << JsonNumber{s.free_volume_m3};
  if (s.has_known_space) {
    json << ", \"known_min\": [" << JsonNumber{s.known_min.x} << ", " << JsonNumber{s.known_min.y} << ", "
         << JsonNumber{s.known_min.z} << "], \"known_max\": [" << JsonNumber{s.known_max.x} << ", "
         << JsonNumber{s.known_max.y} << ", " << JsonNumber{s.known_max.z} << "]";
  } else {
    json << ", \"known_min\": null, \"known_max\": null";
  }
  json << extra << "}";
  return json.str();
}

}  // namespace umbra::cli
