// The collision sections (collision_section.hpp).
#include "collision_section.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>
#include <sstream>
#include <stdexcept>

namespace umbra_bench {
namespace {

/// Squared distance from `p` to the cube of edge `size` centred on `c`.
double squared_distance_to_cube(const umbra::Vec3d& p, const octomap::point3d& c, double size) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max(0.0, std::fabs(p[a] - double(c(a))) - 0.5 * size);
    sum += d * d;
  }
  return sum;
}

octomap::OcTreeKey key_of(const octomap::OcTree& tree, const umbra::Vec3d& p) {
  octomap::OcTreeKey key;
  if (!tree.coordToKeyChecked(p.x, p.y, p.z, key)) throw std::runtime_error("a shape reaches outside OctoMap's extent");
  return key;
}

/// OctoMap, unknown blocking: the voxel loop over the ball's bounding box.
bool octomap_sphere_blocked(const octomap::OcTree& tree, const umbra::Sphere& s) {
  const double res = tree.getResolution();
  const octomap::OcTreeKey low = key_of(tree, s.center - umbra::Vec3d{s.radius, s.radius, s.radius});
  const octomap::OcTreeKey high = key_of(tree, s.center + umbra::Vec3d{s.radius, s.radius, s.radius});
  const double r2 = s.radius * s.radius;
  octomap::OcTreeKey key;
  for (key[2] = low[2]; key[2] <= high[2]; ++key[2]) {
    for (key[1] = low[1]; key[1] <= high[1]; ++key[1]) {
      for (key[0] = low[0]; key[0] <= high[0]; ++key[0]) {
        if (squared_distance_to_cube(s.center, tree.keyToCoord(key), res) > r2) continue;
        const octomap::OcTreeNode* node = tree.search(key);
        if (!octomap_known(tree, node) || tree.isNodeOccupied(node)) return true;
      }
    }
  }
  return false;
}

/// OctoMap, occupied only: the leaves of the ball's bounding box.
bool octomap_sphere_hits_occupied(const octomap::OcTree& tree, const umbra::Sphere& s) {
  const umbra::Vec3d low = s.center - umbra::Vec3d{s.radius, s.radius, s.radius};
  const umbra::Vec3d high = s.center + umbra::Vec3d{s.radius, s.radius, s.radius};
  const double r2 = s.radius * s.radius;
  for (auto it = tree.begin_leafs_bbx(octomap::point3d(float(low.x), float(low.y), float(low.z)),
                                      octomap::point3d(float(high.x), float(high.y), float(high.z))),
            end = tree.end_leafs_bbx();
       it != end; ++it) {
    if (tree.isNodeOccupied(*it) && squared_distance_to_cube(s.center, it.getCoordinate(), it.getSize()) <= r2) {
      return true;
    }
  }
  return false;
}

/// OctoMap: computeRayKeys plus the end voxel, unknown blocking.
bool octomap_segment_blocked(const octomap::OcTree& tree, const umbra::Segment& s, octomap::KeyRay& ray) {
  const octomap::point3d a(float(s.from.x), float(s.from.y), float(s.from.z));
  const octomap::point3d b(float(s.to.x), float(s.to.y), float(s.to.z));
  if (!tree.computeRayKeys(a, b, ray)) throw std::runtime_error("a segment reaches outside OctoMap's extent");
  ray.addKey(key_of(tree, {double(b.x()), double(b.y()), double(b.z())}));
  for (const octomap::OcTreeKey& key : ray) {
    const octomap::OcTreeNode* node = tree.search(key);
    if (!octomap_known(tree, node) || tree.isNodeOccupied(node)) return true;
  }
  return false;
}

/// umbra's batch answer (1 = free), timed: the median of `repeat` runs, in
/// microseconds per shape.
template <typename Shape>
double time_umbra(const umbra::OccupancyMap& map, std::span<const Shape> shapes, const umbra::CollisionOptions& options,
                  int repeat, std::vector<std::uint8_t>& free) {
  free.assign(shapes.size(), 0);
  std::vector<double> runs;
  for (int r = 0; r < repeat; ++r) {
    const double start = thread_seconds();
    map.is_free(shapes, std::span<std::uint8_t>(free), options);
    runs.push_back(1e6 * (thread_seconds() - start) / double(shapes.size()));
  }
  return median(runs);
}

/// Fills the OctoMap columns of `row` from `blocked(i)` over the first
/// checks, comparing with umbra's answers.
template <typename Shape, typename Blocked>
void time_octomap(CollisionRow& row, const umbra::OccupancyMap& map, std::span<const Shape> shapes,
                  const umbra::CollisionOptions& options, const std::vector<std::uint8_t>& umbra_free, int repeat,
                  Blocked blocked) {
  row.octomap_checks = std::min(row.octomap_checks, shapes.size());
  const std::span<const Shape> first = shapes.first(row.octomap_checks);
  std::vector<std::uint8_t> unused;
  row.umbra_us_on_octomap_checks = time_umbra(map, first, options, repeat, unused);
  const double start = thread_seconds();
  for (std::size_t i = 0; i < first.size(); ++i) {
    if (blocked(first[i]) != (umbra_free[i] == 0)) ++row.mismatches;
  }
  row.octomap_us = 1e6 * (thread_seconds() - start) / double(first.size());
}

double blocked_share(const std::vector<std::uint8_t>& free) {
  return double(std::count(free.begin(), free.end(), std::uint8_t{0})) / double(free.size());
}

}  // namespace

std::vector<CollisionRow> run_sphere_checks(const Dataset& data, const CollisionSettings& settings) {
  std::mt19937_64 rng(settings.seed);
  std::vector<umbra::Sphere> spheres;
  for (const umbra::Vec3d& c : sample_free_points(*data.map, settings.checks, rng)) {
    spheres.push_back({c, settings.radius});
  }
  std::vector<CollisionRow> rows;
  for (const bool unknown_blocks : {true, false}) {
    CollisionRow row;
    row.dataset = data.name;
    char what[64];
    std::snprintf(what, sizeof what, "sphere r = %.2f m, %s", settings.radius,
                  unknown_blocks ? "occupied or unknown blocks" : "occupied blocks");
    row.what = what;
    row.checks = spheres.size();
    row.octomap_checks = settings.octomap_checks;
    const umbra::CollisionOptions options{!unknown_blocks, 0};
    std::vector<std::uint8_t> free;
    row.umbra_us = time_umbra(*data.map, std::span<const umbra::Sphere>(spheres), options, settings.repeat, free);
    row.blocked_share = blocked_share(free);
    time_octomap(row, *data.map, std::span<const umbra::Sphere>(spheres), options, free, settings.repeat,
                 [&](const umbra::Sphere& s) {
                   return unknown_blocks ? octomap_sphere_blocked(*data.octree, s)
                                         : octomap_sphere_hits_occupied(*data.octree, s);
                 });
    rows.push_back(row);
  }
  return rows;
}

CollisionRow run_segment_checks(const Dataset& data, const CollisionSettings& settings) {
  std::mt19937_64 rng(settings.seed + 1);
  const std::vector<umbra::Vec3d> starts = sample_free_points(*data.map, settings.checks, rng);
  const std::vector<umbra::Vec3d> candidates = sample_free_points(*data.map, settings.checks, rng);
  std::vector<umbra::Segment> segments;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const umbra::Vec3d d = candidates[i] - starts[i];
    const double length = d.norm();
    const double scale = settings.max_length > 0.0 && length > settings.max_length ? settings.max_length / length : 1.0;
    segments.push_back({starts[i], starts[i] + d * scale});
  }
  CollisionRow row;
  row.dataset = data.name;
  char what[64];
  if (settings.max_length > 0.0) {
    std::snprintf(what, sizeof what, "segment <= %.1f m, occupied or unknown blocks", settings.max_length);
  } else {
    std::snprintf(what, sizeof what, "segment, occupied or unknown blocks");
  }
  row.what = what;
  row.checks = segments.size();
  row.octomap_checks = settings.octomap_checks;
  const umbra::CollisionOptions options{false, 0};
  std::vector<std::uint8_t> free;
  row.umbra_us = time_umbra(*data.map, std::span<const umbra::Segment>(segments), options, settings.repeat, free);
  row.blocked_share = blocked_share(free);
  octomap::KeyRay ray;
  time_octomap(row, *data.map, std::span<const umbra::Segment>(segments), options, free, settings.repeat,
               [&](const umbra::Segment& s) { return octomap_segment_blocked(*data.octree, s, ray); });
  return row;
}

std::string collision_table(const std::vector<CollisionRow>& rows) {
  std::ostringstream out;
  out << "| dataset | check | checks | blocked | umbra us/check | OctoMap checks | OctoMap us/check | "
         "umbra us/check on those | speed-up | answers differ |\n"
      << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CollisionRow& r : rows) {
    char line[512];
    std::snprintf(line, sizeof line, "| %s | %s | %zu | %.1f%% | %.3g | %zu | %.3g | %.3g | %s | %zu |\n",
                  r.dataset.c_str(), r.what.c_str(), r.checks, 100.0 * r.blocked_share, r.umbra_us, r.octomap_checks,
                  r.octomap_us, r.umbra_us_on_octomap_checks, ratio(r.octomap_us, r.umbra_us_on_octomap_checks).c_str(),
                  r.mismatches);
    out << line;
  }
  return out.str();
}

}  // namespace umbra_bench
