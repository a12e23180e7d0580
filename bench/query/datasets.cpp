// The query benchmark's datasets and helpers (datasets.hpp).
#include "datasets.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <time.h>

#include "umbra/io/octomap_files.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra_bench {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double thread_seconds() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, separator)) parts.push_back(part);
  return parts;
}

std::string ratio(double numerator, double denominator) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1fx", numerator / denominator);
  return text;
}

const std::vector<DatasetSpec> kDatasets = {
    {"3dtk-20cm", "3dtk/3dtk_registered.graph", 0.20, 30.0},
    {"3dtk-5cm", "3dtk/3dtk_registered.graph", 0.05, 30.0},
    {"tum-2cm", "tum_fr2_pioneer_slam2", 0.02, 5.0},
    {"geb079-8cm", "octomap/geb079.bt", 0.0, 0.0},
};

Dataset load_dataset(const DatasetSpec& spec, const std::string& data_dir, const std::filesystem::path& scratch) {
  Dataset data;
  data.name = spec.name;
  const std::string input = data_dir + "/" + spec.input;
  const auto start = Clock::now();
  if (spec.resolution == 0.0) {
    data.map = std::make_unique<umbra::OccupancyMap>(umbra::load_octomap(input));
  } else {
    data.map = std::make_unique<umbra::OccupancyMap>(spec.resolution);
    umbra::InsertOptions options;
    options.integrator = umbra::IntegratorKind::discrete;
    options.max_range = spec.max_range;
    const auto source = umbra::open_scan_source(input);
    umbra::Scan scan;
    while (source->next(scan)) data.map->insert_point_cloud(scan.origin, scan.points, options);
  }
  const std::filesystem::path bt = scratch / (spec.name + ".bt");
  umbra::save_octomap(*data.map, bt, umbra::OctoMapFormat::bt);
  data.octree = std::make_unique<octomap::OcTree>(bt.string());
  std::filesystem::remove(bt);
  const umbra::NodeCounts counts = data.map->node_counts();
  std::fprintf(stderr, "%s: %zu umbra nodes, %zu OctoMap nodes, ready in %.1f s\n", spec.name.c_str(),
               counts.total(), data.octree->size(), seconds_since(start));
  return data;
}

std::vector<umbra::Vec3d> sample_free_points(const umbra::OccupancyMap& map, std::size_t count, std::mt19937_64& rng) {
  std::vector<umbra::Node> free_nodes;
  std::vector<double> cumulative;
  double total = 0.0;
  for (const umbra::Node& node : map.query(umbra::pred::leaf() && umbra::pred::free())) {
    free_nodes.push_back(node);
    total += std::pow(8.0, node.depth);
    cumulative.push_back(total);
  }
  if (free_nodes.empty()) throw std::runtime_error("the map has no free voxel to place poses in");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<umbra::Vec3d> points;
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = unit(rng) * total;
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), pick);
    const umbra::Node& node = free_nodes[std::min<std::size_t>(it - cumulative.begin(), free_nodes.size() - 1)];
    const umbra::Vec3d low = node.min_corner();
    points.push_back({low.x + unit(rng) * node.size, low.y + unit(rng) * node.size, low.z + unit(rng) * node.size});
  }
  return points;
}

}  // namespace umbra_bench
