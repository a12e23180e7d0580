// Query benchmark: umbra's queries against liboctomap on the same maps, in
// one run (issue 8; results and commands in docs/benchmarks.md).
//
// Datasets (each map built once, then written as .bt and read back by
// liboctomap, so that both libraries answer on the same voxels):
//   3dtk-20cm, 3dtk-5cm  the three 3DTK scans (3dtk/3dtk_registered.graph),
//                        umbra's discrete integrator, max range 30 m
//   tum-2cm              the ten TUM RGB-D frames, discrete, max range 5 m
//   geb079-8cm           octomap/geb079.bt read as it is
// Sections, one per kind of query (--sections picks them):
//   gain  information gain of 100 poses (hfov 115, vfov 60 deg, 0 to 6.5 m;
//         positions uniform in the free voxels, yaw uniform, pitch in
//         [-15, 15] deg, fixed seed): umbra exact and fast, and the
//         OctoMap-style baseline of receding-horizon explorers (a voxel by
//         voxel loop over the frustum's bounding box, search() for unknown,
//         then computeRayKeys and search() per key for visibility) on the
//         first --octomap-poses poses of each dataset (it takes seconds per
//         pose at 5 cm and minutes at 2 cm). Every count is compared: umbra
//         exact must equal OctoMap-style; fast is reported with its error.
// One thread throughout; times are the thread's CPU time (the machines are
// shared), for umbra the median of --repeat runs.
//
// Usage: umbra_query_benchmark [--data DIR] [--datasets 3dtk-20cm,3dtk-5cm,tum-2cm,geb079-8cm]
//          [--sections gain] [--poses 100] [--octomap-poses 3dtk-20cm=100,3dtk-5cm=10,...]
//          [--repeat 3] [--seed 1] [--exact-only] [--markdown FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <time.h>
#include <unistd.h>

#include <octomap/OcTree.h>

#include "umbra/io/octomap_files.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// CPU time of the calling thread, in seconds: the machines are shared, and
/// a query's own CPU time is what other processes disturb least.
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

std::vector<std::string> split(const std::string& text, char separator = ',') {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, separator)) parts.push_back(part);
  return parts;
}

// --- datasets -------------------------------------------------------------------------

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

/// Points uniformly distributed over the free finest voxels of the map.
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

// --- information gain ------------------------------------------------------------------

/// The pose kind of issue 8: hfov 115 deg, vfov 60 deg, 0 to 6.5 m.
std::vector<umbra::Frustum> gain_poses(const umbra::OccupancyMap& map, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const std::vector<umbra::Vec3d> positions = sample_free_points(map, count, rng);
  std::uniform_real_distribution<double> yaw(0.0, 360.0);
  std::uniform_real_distribution<double> pitch(-15.0, 15.0);
  std::vector<umbra::Frustum> poses;
  for (const umbra::Vec3d& p : positions) {
    poses.push_back(umbra::Frustum::from_degrees(p, yaw(rng), pitch(rng), 115.0, 60.0, 0.0, 6.5));
  }
  return poses;
}

/// The gain as receding-horizon explorers compute it with OctoMap: every
/// voxel of the frustum's bounding box, search() to find the unknown ones
/// (no node, or a value between the thresholds), and for those
/// computeRayKeys from the sensor with search() per key, blocked by the
/// first occupied voxel.
std::uint64_t octomap_style_gain(const octomap::OcTree& tree, const umbra::Frustum& frustum) {
  const double res = tree.getResolution();
  const umbra::Vec3d o = frustum.origin;
  const double range = frustum.max_range;
  // Bounding box: the pyramid cut at distance `range` along f (its apex and
  // four far corners) within the ball of radius `range`.
  const umbra::Vec3d f = frustum.forward();
  const umbra::Vec3d l = frustum.left();
  const umbra::Vec3d u = frustum.up();
  umbra::Vec3d low = o;
  umbra::Vec3d high = o;
  const double th = std::tan(frustum.hfov / 2);
  const double tv = std::tan(frustum.vfov / 2);
  for (const double sh : {-1.0, 1.0}) {
    for (const double sv : {-1.0, 1.0}) {
      const umbra::Vec3d corner = o + (f + l * (sh * th) + u * (sv * tv)) * range;
      for (int a = 0; a < 3; ++a) {
        low[a] = std::min(low[a], corner[a]);
        high[a] = std::max(high[a], corner[a]);
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    low[a] = std::max(low[a], o[a] - range);
    high[a] = std::min(high[a], o[a] + range);
  }
  octomap::OcTreeKey low_key;
  octomap::OcTreeKey high_key;
  if (!tree.coordToKeyChecked(octomap::point3d(float(low.x), float(low.y), float(low.z)), low_key) ||
      !tree.coordToKeyChecked(octomap::point3d(float(high.x), float(high.y), float(high.z)), high_key)) {
    throw std::runtime_error("frustum outside OctoMap's extent");
  }
  const octomap::point3d origin(float(o.x), float(o.y), float(o.z));
  octomap::KeyRay ray;
  std::uint64_t gain = 0;
  octomap::OcTreeKey key;
  for (key[2] = low_key[2]; key[2] <= high_key[2]; ++key[2]) {
    for (key[1] = low_key[1]; key[1] <= high_key[1]; ++key[1]) {
      for (key[0] = low_key[0]; key[0] <= high_key[0]; ++key[0]) {
        const octomap::point3d c = tree.keyToCoord(key);
        if (!frustum.contains(umbra::Vec3d{tree.keyToCoord(key[0]), tree.keyToCoord(key[1]), tree.keyToCoord(key[2])})) {
          continue;
        }
        const octomap::OcTreeNode* node = tree.search(key);
        if (node != nullptr && (node->getLogOdds() > tree.getOccupancyThresLog() ||
                                node->getLogOdds() < tree.getOccupancyThresLog())) {
          continue;  // known: free or occupied (thresholds 0.5: only the absent voxels are unknown)
        }
        if (!tree.computeRayKeys(origin, c, ray)) continue;
        bool visible = true;
        for (const octomap::OcTreeKey& k : ray) {
          const octomap::OcTreeNode* n = tree.search(k);
          if (n != nullptr && tree.isNodeOccupied(n)) {
            visible = false;
            break;
          }
        }
        if (visible) ++gain;
      }
    }
  }
  (void)res;
  return gain;
}

struct GainRow {
  std::string dataset;
  std::size_t poses = 0;
  double exact_us = 0.0;
  double fast_us = 0.0;
  double exact_batch_us = 0.0;  // per pose, the poses as one batch (scratch memory reused)
  double fast_batch_us = 0.0;
  std::size_t octomap_poses = 0;
  double octomap_us = 0.0;
  double exact_us_on_octomap_poses = 0.0;
  double fast_us_on_octomap_poses = 0.0;
  std::size_t octomap_mismatches = 0;
  double mean_unknown = 0.0;
  double fast_mean_error = 0.0;  // relative to exact, over poses with a non-zero exact gain
  double fast_max_error = 0.0;
  double fast_total_error = 0.0;  // sum of |fast - exact| over the sum of exact
  std::uint64_t worst_exact = 0;  // the pose with the largest relative error
  std::uint64_t worst_fast = 0;
};

/// Median over `repeat` runs of the time of each pose, in microseconds.
std::vector<double> time_umbra(const umbra::OccupancyMap& map, const std::vector<umbra::Frustum>& poses,
                               const umbra::GainOptions& options, int repeat, std::vector<std::uint64_t>& counts) {
  std::vector<std::vector<double>> runs(poses.size());
  counts.assign(poses.size(), 0);
  for (int r = 0; r < repeat; ++r) {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const double start = thread_seconds();
      const umbra::GainResult gain = map.information_gain(poses[i], options);
      runs[i].push_back(1e6 * (thread_seconds() - start));
      counts[i] = gain.unknown_voxels;
    }
  }
  std::vector<double> us;
  for (auto& per_pose : runs) us.push_back(median(per_pose));
  return us;
}

GainRow run_gain(const Dataset& data, std::size_t pose_count, std::size_t octomap_pose_count, int repeat,
                 std::uint64_t seed, bool run_fast) {
  GainRow row;
  row.dataset = data.name;
  const std::vector<umbra::Frustum> poses = gain_poses(*data.map, pose_count, seed);
  row.poses = poses.size();
  std::vector<std::uint64_t> exact;
  std::vector<std::uint64_t> fast;
  const std::vector<double> exact_us = time_umbra(*data.map, poses, {.method = umbra::GainMethod::exact}, repeat, exact);
  const std::vector<double> fast_us = run_fast ? time_umbra(*data.map, poses, {.method = umbra::GainMethod::fast}, repeat, fast)
                                              : std::vector<double>(poses.size(), 0.0);
  if (!run_fast) fast = exact;
  // The same poses as one batch (one thread: the scratch memory is reused
  // from pose to pose); the answers must not change.
  for (const umbra::GainMethod method : {umbra::GainMethod::exact, umbra::GainMethod::fast}) {
    if (method == umbra::GainMethod::fast && !run_fast) break;
    std::vector<double> runs;
    for (int r = 0; r < repeat; ++r) {
      const double start = thread_seconds();
      const std::vector<umbra::GainResult> batch =
          data.map->information_gain(std::span<const umbra::Frustum>(poses), {.method = method});
      runs.push_back(1e6 * (thread_seconds() - start) / double(poses.size()));
      const std::vector<std::uint64_t>& single = method == umbra::GainMethod::exact ? exact : fast;
      for (std::size_t i = 0; i < poses.size(); ++i) {
        if (batch[i].unknown_voxels != single[i]) {
          std::fprintf(stderr, "%s pose %zu: the batch answered %llu, the single call %llu\n", data.name.c_str(), i,
                       static_cast<unsigned long long>(batch[i].unknown_voxels),
                       static_cast<unsigned long long>(single[i]));
        }
      }
    }
    (method == umbra::GainMethod::exact ? row.exact_batch_us : row.fast_batch_us) = median(runs);
  }
  double sum_error = 0.0;
  double sum_exact = 0.0;
  double sum_difference = 0.0;
  std::size_t with_gain = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    row.exact_us += exact_us[i] / double(poses.size());
    row.fast_us += fast_us[i] / double(poses.size());
    row.mean_unknown += double(exact[i]) / double(poses.size());
    sum_exact += double(exact[i]);
    sum_difference += std::fabs(double(fast[i]) - double(exact[i]));
    if (exact[i] > 0) {
      const double error = std::fabs(double(fast[i]) - double(exact[i])) / double(exact[i]);
      sum_error += error;
      if (error > row.fast_max_error) {
        row.fast_max_error = error;
        row.worst_exact = exact[i];
        row.worst_fast = fast[i];
      }
      ++with_gain;
    }
  }
  row.fast_total_error = sum_exact > 0.0 ? sum_difference / sum_exact : 0.0;
  row.fast_mean_error = with_gain ? sum_error / double(with_gain) : 0.0;
  row.octomap_poses = std::min(octomap_pose_count, poses.size());
  for (std::size_t i = 0; i < row.octomap_poses; ++i) {
    const double start = thread_seconds();
    const std::uint64_t theirs = octomap_style_gain(*data.octree, poses[i]);
    const double us = 1e6 * (thread_seconds() - start);
    row.octomap_us += us / double(row.octomap_poses);
    row.exact_us_on_octomap_poses += exact_us[i] / double(row.octomap_poses);
    row.fast_us_on_octomap_poses += fast_us[i] / double(row.octomap_poses);
    if (theirs != exact[i]) {
      ++row.octomap_mismatches;
      std::fprintf(stderr, "%s pose %zu: OctoMap-style %llu, umbra exact %llu\n", data.name.c_str(), i,
                   static_cast<unsigned long long>(theirs), static_cast<unsigned long long>(exact[i]));
    }
    std::fprintf(stderr, "%s pose %zu: OctoMap-style %.0f us (umbra exact %.0f us, fast %.0f us), gain %llu\n",
                 data.name.c_str(), i, us, exact_us[i], fast_us[i], static_cast<unsigned long long>(theirs));
  }
  return row;
}

std::string ratio(double numerator, double denominator) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1fx", numerator / denominator);
  return text;
}

std::string gain_table(const std::vector<GainRow>& rows) {
  std::ostringstream out;
  out << "| dataset | poses | mean gain (voxels) | umbra exact us/pose | umbra fast us/pose | "
         "fast error: mean / max per pose (worst: exact -> fast) / of the summed gains | OctoMap-style poses timed | "
         "OctoMap-style us/pose | exact speed-up | fast speed-up | exact = OctoMap-style |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const GainRow& r : rows) {
    char line[768];
    const bool timed = r.octomap_poses > 0;
    const std::string same = r.octomap_mismatches == 0 ? "yes" : std::to_string(r.octomap_mismatches) + " poses differ";
    std::snprintf(line, sizeof line,
                  "| %s | %zu | %.0f | %.0f | %.0f | %.2f%% / %.1f%% (%llu -> %llu) / %.2f%% | %zu | %s | %s | %s | %s |\n",
                  r.dataset.c_str(), r.poses, r.mean_unknown, r.exact_us, r.fast_us, 100.0 * r.fast_mean_error,
                  100.0 * r.fast_max_error, static_cast<unsigned long long>(r.worst_exact),
                  static_cast<unsigned long long>(r.worst_fast), 100.0 * r.fast_total_error, r.octomap_poses,
                  timed ? std::to_string(static_cast<long long>(r.octomap_us)).c_str() : "-",
                  timed ? ratio(r.octomap_us, r.exact_us_on_octomap_poses).c_str() : "-",
                  timed ? ratio(r.octomap_us, r.fast_us_on_octomap_poses).c_str() : "-", timed ? same.c_str() : "-");
    out << line;
  }
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string data_dir = "../shared/data";
  std::string dataset_names = "3dtk-20cm,3dtk-5cm,tum-2cm,geb079-8cm";
  std::string sections = "gain";
  std::string octomap_poses_text = "3dtk-20cm=100,3dtk-5cm=10,tum-2cm=2,geb079-8cm=20";
  std::string markdown_path;
  std::size_t poses = 100;
  int repeat = 3;
  bool run_fast = true;
  std::uint64_t seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--data") data_dir = value();
    else if (arg == "--datasets") dataset_names = value();
    else if (arg == "--sections") sections = value();
    else if (arg == "--poses") poses = std::stoul(value());
    else if (arg == "--octomap-poses") octomap_poses_text = value();
    else if (arg == "--repeat") repeat = std::stoi(value());
    else if (arg == "--exact-only") run_fast = false;
    else if (arg == "--seed") seed = std::stoull(value());
    else if (arg == "--markdown") markdown_path = value();
    else if (arg == "--help" || arg == "-h") {
      std::printf(
          "usage: umbra_query_benchmark [--data DIR] [--datasets LIST] [--sections gain] [--poses 100]\n"
          "         [--octomap-poses NAME=N,...] [--repeat 3] [--seed 1] [--exact-only] [--markdown FILE]\n"
          "datasets:");
      for (const DatasetSpec& d : kDatasets) std::printf(" %s", d.name.c_str());
      std::printf("\n");
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s (see the comment at the top of bench/query_benchmark.cpp)\n",
                   arg.c_str());
      return 2;
    }
  }
  std::map<std::string, std::size_t> octomap_poses;
  for (const std::string& item : split(octomap_poses_text)) {
    const std::vector<std::string> parts = split(item, '=');
    if (parts.size() != 2) {
      std::fprintf(stderr, "--octomap-poses wants NAME=N items, got %s\n", item.c_str());
      return 2;
    }
    octomap_poses[parts[0]] = std::stoul(parts[1]);
  }
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() / ("umbra_query_benchmark_" + std::to_string(::getpid()));
  std::filesystem::create_directories(scratch);

  std::string report;
  std::vector<GainRow> gain_rows;
  for (const std::string& name : split(dataset_names)) {
    const auto spec = std::find_if(kDatasets.begin(), kDatasets.end(), [&](const DatasetSpec& d) { return d.name == name; });
    if (spec == kDatasets.end()) {
      std::fprintf(stderr, "unknown dataset %s (see --help)\n", name.c_str());
      return 2;
    }
    Dataset data;
    try {
      data = load_dataset(*spec, data_dir, scratch);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cannot load %s: %s\n", name.c_str(), e.what());
      return 1;
    }
    for (const std::string& section : split(sections)) {
      if (section == "gain") {
        gain_rows.push_back(
            run_gain(data, poses, octomap_poses.count(name) ? octomap_poses[name] : 0, repeat, seed, run_fast));
        std::fputs(gain_table({gain_rows.back()}).c_str(), stderr);
        std::fprintf(stderr, "batch: exact %.0f us/pose, fast %.0f us/pose\n", gain_rows.back().exact_batch_us,
                     gain_rows.back().fast_batch_us);
      } else {
        std::fprintf(stderr, "unknown section %s\n", section.c_str());
        return 2;
      }
    }
  }
  std::filesystem::remove_all(scratch);
  if (!gain_rows.empty()) report += "### Information gain\n\n" + gain_table(gain_rows) + "\n";
  std::printf("%s", report.c_str());
  if (!markdown_path.empty()) std::ofstream(markdown_path) << report;
  return 0;
}
