// Shared parts of the query benchmark (bench/query/query_benchmark.cpp):
// the datasets, each map built once by umbra and read by liboctomap through
// a .bt file so that both libraries answer on the same voxels; free-space
// sampling for poses and shapes; CPU-time helpers.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "umbra/map/occupancy_map.hpp"

namespace umbra_bench {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start);
/// CPU time of the calling thread, in seconds: the machines are shared, and
/// a query's own CPU time is what other processes disturb least.
double thread_seconds();
double median(std::vector<double> values);
std::vector<std::string> split(const std::string& text, char separator = ',');
/// "12.3x"
std::string ratio(double numerator, double denominator);

struct Dataset {
  std::string name;
  std::unique_ptr<umbra::OccupancyMap> map;
  std::unique_ptr<octomap::OcTree> octree;  // the same map, through a .bt file
};

struct DatasetSpec {
  std::string name;
  std::string input;  // relative to --data
  double resolution;  // 0: the file's own
  double max_range;
};

extern const std::vector<DatasetSpec> kDatasets;

Dataset load_dataset(const DatasetSpec& spec, const std::string& data_dir, const std::filesystem::path& scratch);

/// Points uniformly distributed over the free finest voxels of the map.
std::vector<umbra::Vec3d> sample_free_points(const umbra::OccupancyMap& map, std::size_t count, std::mt19937_64& rng);

/// Whether OctoMap's voxel is known (a node whose value is not the
/// threshold), so unknown exactly where umbra's state is unknown.
inline bool octomap_known(const octomap::OcTree& tree, const octomap::OcTreeNode* node) {
  return node != nullptr && node->getLogOdds() != tree.getOccupancyThresLog();
}

}  // namespace umbra_bench
