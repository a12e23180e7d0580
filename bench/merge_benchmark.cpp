// Merge benchmark: OccupancyMap::merge against inserting the same scans, and
// against what OctoMap users write to merge two trees, in one run.
//
// For every dataset/resolution pair the scans are split in two halves; each
// half is inserted into a map of its own (umbra: the simple integrator on one
// thread, as the merge runs; OctoMap: insertPointCloud without
// discretisation, the same voxels). Timed, median of --repeat runs, each on a
// fresh copy of the first half's map:
//   insert-all    umbra: all scans into one empty map (the reference cost)
//   merge         umbra: first.merge(second)
//   merge-turned  umbra: first.merge(second, T), T a 1 degree turn about z
//                 and a 0.3-voxel shift (resampled, voxel by voxel)
//   octomap-loop  OctoMap: for each leaf of the second tree (expanded to
//                 finest voxels first, untimed, so that pruned leaves count
//                 for all their voxels) first.updateNode(key, log-odds)
// It also reports how far the merged map is from the map of all scans:
// leaves of the whole map whose value the merged map does not hold (beyond
// 1e-4: float rounding is below that), with the default clamping bounds
// and with bounds no voxel reaches (clamp 1e-6 / 1 - 1e-6: +-13.8, more
// than 16 hits), and the voxels
// whose state differs (umbra::compare_maps).
//
// Usage: umbra_merge_benchmark [--data DIR] [--runs 3dtk:0.05,tum:0.02] [--repeat 3]
//          [--max-range 30] [--tum-max-range 5] [--markdown FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "bench_data.hpp"
#include "common/argument_cursor.hpp"
#include "umbra/map/map_agreement.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using namespace umbra;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

OccupancyMap insert(const std::vector<Scan>& scans, std::size_t begin, std::size_t end, const MapConfig& config,
                    double max_range) {
  OccupancyMap map(config);
  InsertOptions options;
  options.integrator = IntegratorKind::simple;
  options.max_range = max_range;
  options.threads = 1;  // merging runs on one thread: compare like with like
  for (std::size_t i = begin; i < end; ++i) map.insert_point_cloud(scans[i].origin, scans[i].points, options);
  return map;
}

void insert_octomap(octomap::OcTree& tree, const std::vector<Scan>& scans, std::size_t begin, std::size_t end,
                    double max_range) {
  for (std::size_t i = begin; i < end; ++i) {
    octomap::Pointcloud cloud;
    cloud.reserve(scans[i].points.size());
    for (const Vec3f& p : scans[i].points) cloud.push_back(p.x, p.y, p.z);
    const Vec3f o = scans[i].origin;
    tree.insertPointCloud(cloud, octomap::point3d(o.x, o.y, o.z), max_range, false, false);
  }
}

/// Voxels of `whole` whose value `merged` does not hold within 1e-4 (a
/// pruned node of either map counts for all its voxels).
std::uint64_t differing_below(const OccupancyMap& merged, Key key, int depth, float value) {
  const Node there = merged.node(key, depth);
  if (!there.has_children) return std::abs(there.log_odds - value) > 1e-4f ? std::uint64_t{1} << (3 * depth) : 0;
  std::uint64_t differing = 0;
  const std::uint32_t half = 1u << (depth - 1);
  for (unsigned slot = 0; slot < 8; ++slot) {
    const Key child{key.x + ((slot & 1u) != 0 ? half : 0), key.y + ((slot & 2u) != 0 ? half : 0),
                    key.z + ((slot & 4u) != 0 ? half : 0)};
    differing += differing_below(merged, child, depth - 1, value);
  }
  return differing;
}

std::uint64_t differing_voxels(const OccupancyMap& whole, const OccupancyMap& merged) {
  std::uint64_t differing = 0;
  whole.for_each_leaf(
      [&](const Node& leaf) { differing += differing_below(merged, leaf.key, leaf.depth, leaf.log_odds); });
  return differing;
}

std::uint64_t state_differences(const OccupancyMap& a, const OccupancyMap& b) {
  const MapAgreement agreement = compare_maps(a, b);
  std::uint64_t differing = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) differing += i == j ? 0 : agreement.voxels[i][j];
  }
  return differing;
}

struct Row {
  std::string dataset;
  double resolution;
  std::size_t scans;
  double insert_all, merge, merge_turned, octomap_loop;
  std::uint64_t merge_voxels, merge_nodes, octomap_leaves;
  std::uint64_t differing_default, differing_wide, states_default;
};

Row run(const bench::Dataset& data, double resolution, int repeat) {
  Row row{data.name, resolution, data.scans.size(), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const std::size_t half = data.scans.size() / 2;
  const std::size_t all = data.scans.size();
  MapConfig config;
  config.resolution = resolution;
  const OccupancyMap first = insert(data.scans, 0, half, config, data.max_range);
  const OccupancyMap second = insert(data.scans, half, all, config, data.max_range);
  octomap::OcTree octo_first(resolution);
  octomap::OcTree octo_second(resolution);
  insert_octomap(octo_first, data.scans, 0, half, data.max_range);
  insert_octomap(octo_second, data.scans, half, all, data.max_range);
  octo_second.expand();
  const double angle = std::numbers::pi / 180.0;
  const Pose turn = Pose::from_translation_quaternion(0.3 * resolution, 0, 0, std::cos(angle / 2), 0, 0,
                                                      std::sin(angle / 2));
  std::vector<double> insert_all, merge, merge_turned, octomap_loop;
  for (int r = 0; r < repeat; ++r) {
    auto start = Clock::now();
    const OccupancyMap whole = insert(data.scans, 0, all, config, data.max_range);
    insert_all.push_back(seconds_since(start));

    OccupancyMap merged = first;
    start = Clock::now();
    const MergeStats stats = merged.merge(second);
    merge.push_back(seconds_since(start));
    row.merge_voxels = stats.voxels;
    row.merge_nodes = stats.nodes;

    OccupancyMap turned = first;
    start = Clock::now();
    turned.merge(second, turn);
    merge_turned.push_back(seconds_since(start));

    octomap::OcTree octo_merged(octo_first);
    std::uint64_t leaves = 0;
    start = Clock::now();
    for (auto it = octo_second.begin_leafs(), end = octo_second.end_leafs(); it != end; ++it) {
      octo_merged.updateNode(it.getKey(), it->getLogOdds());
      ++leaves;
    }
    octomap_loop.push_back(seconds_since(start));
    row.octomap_leaves = leaves;
    if (r == 0) {
      row.differing_default = differing_voxels(whole, merged);
      row.states_default = state_differences(whole, merged);
    }
  }
  // The same with bounds no voxel reaches.
  MapConfig wide = config;
  wide.sensor.clamp_min = 1e-6;
  wide.sensor.clamp_max = 1.0 - 1e-6;
  const OccupancyMap wide_whole = insert(data.scans, 0, all, wide, data.max_range);
  OccupancyMap wide_merged = insert(data.scans, 0, half, wide, data.max_range);
  wide_merged.merge(insert(data.scans, half, all, wide, data.max_range));
  row.differing_wide = differing_voxels(wide_whole, wide_merged);
  row.insert_all = bench::median(insert_all);
  row.merge = bench::median(merge);
  row.merge_turned = bench::median(merge_turned);
  row.octomap_loop = bench::median(octomap_loop);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  bench::DatasetOptions data_options;
  std::string runs = "3dtk:0.05,tum:0.02";
  int repeat = 3;
  std::string markdown;
  for (umbra_bench::ArgumentCursor args{argc, argv}; args.next();) {
    const std::string flag = args.flag();
    if (flag == "--data") {
      data_options.data_dir = args.value();
    } else if (flag == "--runs") {
      runs = args.value();
    } else if (flag == "--repeat") {
      repeat = std::stoi(args.value());
    } else if (flag == "--max-range") {
      data_options.max_range = std::stod(args.value());
    } else if (flag == "--tum-max-range") {
      data_options.tum_max_range = std::stod(args.value());
    } else if (flag == "--markdown") {
      markdown = args.value();
    } else if (flag == "--help") {
      std::puts("umbra_merge_benchmark [--data DIR] [--runs 3dtk:0.05,tum:0.02] [--repeat 3] [--max-range 30] "
                "[--tum-max-range 5] [--markdown FILE]");
      return 0;
    } else {
      std::fprintf(stderr, "unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  std::ostringstream table;
  table << "| data | res | scans | insert all (s) | merge (s) | merge / insert | merge turned (s) | OctoMap loop (s) "
           "| voxels merged | node additions | OctoMap leaves | voxels differing, default clamp "
           "| voxels differing, wide clamp | states differing, default clamp |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& item : bench::split_list(runs)) {
    const std::size_t colon = item.find(':');
    if (colon == std::string::npos) {
      std::fprintf(stderr, "--runs: expected dataset:resolution, got '%s'\n", item.c_str());
      return 2;
    }
    const bench::Dataset data = bench::load_dataset(item.substr(0, colon), data_options);
    const Row r = run(data, std::stod(item.substr(colon + 1)), repeat);
    char line[512];
    std::snprintf(line, sizeof line,
                  "| %s | %g | %zu | %.3f | %.4f | %.3f | %.3f | %.3f | %llu | %llu | %llu | %llu | %llu | %llu |\n",
                  r.dataset.c_str(), r.resolution, r.scans, r.insert_all, r.merge, r.merge / r.insert_all,
                  r.merge_turned, r.octomap_loop, static_cast<unsigned long long>(r.merge_voxels),
                  static_cast<unsigned long long>(r.merge_nodes), static_cast<unsigned long long>(r.octomap_leaves),
                  static_cast<unsigned long long>(r.differing_default),
                  static_cast<unsigned long long>(r.differing_wide),
                  static_cast<unsigned long long>(r.states_default));
    std::fputs(line, stdout);
    std::fflush(stdout);
    table << line;
  }
  std::printf("\n%s", table.str().c_str());
  if (!markdown.empty()) std::ofstream(markdown) << table.str();
  return 0;
}
