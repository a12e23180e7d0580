// The information-gain section (gain_section.hpp).
#include "gain_section.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <span>
#include <sstream>
#include <stdexcept>

namespace umbra_bench {
namespace {

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
        if (octomap_known(tree, node)) {
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

}  // namespace

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
}  // namespace umbra_bench
