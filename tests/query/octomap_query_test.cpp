// Queries against the real liboctomap on the same map: the simulated LiDAR
// in the procedural building (and the real 3DTK scans when ../shared/data is
// there), inserted into both libraries with the same semantics (their maps
// agree voxel for voxel: tests/integrate/octomap_differential_test.cpp).
// Then the same queries, asked as OctoMap users ask them:
//  - ray casts: OcTree::castRay against cast_ray_octomap (hit and end point),
//    for unknown ignored or not and with and without a range;
//  - sphere collision: search() for every voxel whose cube meets the sphere
//    (a missing node is unknown), against is_free(sphere);
//  - segments: computeRayKeys plus the end key, search() for each.
// Every answer must be the same.
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "support/test_support.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

struct Maps {
  OccupancyMap umbra;
  octomap::OcTree octree;
};

Maps build(const std::vector<Scan>& scans, double resolution, double max_range) {
  Maps maps{OccupancyMap(resolution), octomap::OcTree(resolution)};
  InsertOptions options;
  options.integrator = IntegratorKind::discrete;
  options.max_range = max_range;
  for (const Scan& scan : scans) {
    octomap::Pointcloud cloud;
    for (const Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
    maps.octree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), max_range,
                                 false, true);
    maps.umbra.insert_point_cloud(scan.origin, scan.points, options);
  }
  return maps;
}

/// What an OctoMap user checks for a ball: every voxel of the ball's box
/// whose cube meets the ball, looked up one by one.
bool octomap_sphere_free(const octomap::OcTree& tree, Vec3d c, double r, bool unknown_blocks) {
  const double res = tree.getResolution();
  const octomap::OcTreeKey low = tree.coordToKey(octomap::point3d(float(c.x - r), float(c.y - r), float(c.z - r)));
  const octomap::OcTreeKey high = tree.coordToKey(octomap::point3d(float(c.x + r), float(c.y + r), float(c.z + r)));
  for (unsigned x = low[0]; x <= high[0]; ++x) {
    for (unsigned y = low[1]; y <= high[1]; ++y) {
      for (unsigned z = low[2]; z <= high[2]; ++z) {
        const octomap::OcTreeKey key(x, y, z);
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) {
          const double lo = tree.keyToCoord(key[a]) - res / 2;
          const double hi = lo + res;
          const double p = c[a];
          const double d = p < lo ? lo - p : (p > hi ? p - hi : 0.0);
          d2 += d * d;
        }
        if (d2 > r * r) continue;
        const octomap::OcTreeNode* node = tree.search(key);
        if (node == nullptr ? unknown_blocks : tree.isNodeOccupied(node)) return false;
      }
    }
  }
  return true;
}

bool octomap_segment_free(const octomap::OcTree& tree, Vec3d a, Vec3d b, bool unknown_blocks) {
  const octomap::point3d from(float(a.x), float(a.y), float(a.z));
  const octomap::point3d to(float(b.x), float(b.y), float(b.z));
  octomap::KeyRay ray;
  tree.computeRayKeys(from, to, ray);
  std::vector<octomap::OcTreeKey> keys(ray.begin(), ray.end());
  keys.push_back(tree.coordToKey(to));
  for (const octomap::OcTreeKey& key : keys) {
    const octomap::OcTreeNode* node = tree.search(key);
    if (node == nullptr ? unknown_blocks : tree.isNodeOccupied(node)) return false;
  }
  return true;
}

/// Free voxel centres of the map: where a planner would ask from.
std::vector<Vec3d> free_points(const OccupancyMap& map, std::size_t count, unsigned seed) {
  std::vector<Vec3d> all;
  for (const Node& node : map.query(pred::leaf() && pred::free())) {
    if (node.depth == 0) all.push_back(node.center);
  }
  std::mt19937 rng(seed);
  std::vector<Vec3d> out;
  std::uniform_int_distribution<std::size_t> pick(0, all.size() - 1);
  for (std::size_t i = 0; i < count && !all.empty(); ++i) out.push_back(all[pick(rng)]);
  return out;
}

void compare_queries(const Maps& maps, const std::string& name) {
  SCOPED_TRACE(name);
  const std::vector<Vec3d> starts = free_points(maps.umbra, 400, 17);
  ASSERT_GT(starts.size(), 100u);
  std::mt19937 rng(5);
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> radius(0.05, 0.5);
  std::size_t hits = 0;
  std::size_t free_spheres = 0;
  std::size_t free_segments = 0;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const Vec3d o = starts[i];
    // Ray casts.
    const Vec3d d{n(rng), n(rng), n(rng)};
    for (const bool ignore_unknown : {false, true}) {
      for (const double range : {-1.0, 3.0}) {
        octomap::point3d end;
        const bool theirs = maps.octree.castRay(octomap::point3d(float(o.x), float(o.y), float(o.z)),
                                                octomap::point3d(float(d.x), float(d.y), float(d.z)), end,
                                                ignore_unknown, range);
        Vec3f mine_end;
        const bool mine = maps.umbra.cast_ray_octomap(Vec3f(o), Vec3f(d), mine_end, ignore_unknown, range);
        ASSERT_EQ(mine, theirs) << "ray " << i << " ignore_unknown " << ignore_unknown << " range " << range;
        EXPECT_EQ(mine_end, (Vec3f{end.x(), end.y(), end.z()})) << "ray " << i;
        hits += mine;
      }
    }
    // Spheres, with unknown blocking and without.
    const double r = radius(rng);
    for (const bool unknown_blocks : {true, false}) {
      const bool theirs = octomap_sphere_free(maps.octree, o, r, unknown_blocks);
      const bool mine = maps.umbra.is_free(Sphere{o, r}, {!unknown_blocks, 0}).free;
      ASSERT_EQ(mine, theirs) << "sphere " << i << " r " << r << " unknown blocks " << unknown_blocks;
      free_spheres += mine;
    }
    // Segments to another free point.
    const Vec3d to = starts[(i * 7 + 3) % starts.size()];
    for (const bool unknown_blocks : {true, false}) {
      const bool theirs = octomap_segment_free(maps.octree, o, to, unknown_blocks);
      const bool mine = maps.umbra.is_free(Segment{o, to}, {!unknown_blocks, 0}).free;
      ASSERT_EQ(mine, theirs) << "segment " << i << " unknown blocks " << unknown_blocks;
      free_segments += mine;
    }
  }
  // Both answers occurred for every kind.
  EXPECT_GT(hits, 0u);
  EXPECT_GT(free_spheres, 0u);
  EXPECT_LT(free_spheres, 2 * starts.size());
  EXPECT_GT(free_segments, 0u);
  EXPECT_LT(free_segments, 2 * starts.size());
}

TEST(OctomapQueries, ProceduralBuildingWithSimulatedLidar) {
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  lidar.range_noise_stddev = 0.02;
  std::vector<Scan> scans;
  const auto path = sim::demo_path();
  for (std::size_t i = 0; i < path.size(); i += 4) {
    scans.push_back({static_cast<Vec3f>(path[i].position), sim::simulate_scan(scene, path[i], lidar), {}, {}, {}});
  }
  compare_queries(build(scans, 0.1, 30.0), "procedural building at 10 cm");
}

TEST(OctomapQueries, RealRegisteredScans) {
  UMBRA_REQUIRE_SHARED_DATA(path, "3dtk/3dtk_registered.graph");
  std::vector<Scan> scans = test::read_all(path);
  ASSERT_EQ(scans.size(), 3u);
  compare_queries(build(scans, 0.2, 30.0), "3DTK scans at 20 cm");
}

}  // namespace
}  // namespace umbra
