// Differential test against the real liboctomap: the same scans, the same
// sensor model, OctoMap's insertPointCloud (discretize off and on) against
// umbra's simple and discrete integrators; every finest voxel known to
// either map is compared. Agreement must be at least 99.9% of the known
// voxels (in practice it is 100% and the log-odds are bit-identical; see
// docs/octomap-agreement.md). The figures are printed and recorded as test
// properties.
#include <cstdio>
#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "support/test_support.hpp"
#include "support/map_internals.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

struct Agreement {
  std::uint64_t octomap_known = 0;     // voxels with a leaf in OctoMap
  std::uint64_t umbra_known = 0;       // voxels umbra classifies occupied or free
  std::uint64_t both_known = 0;
  std::uint64_t same_class = 0;        // known to OctoMap, same class in umbra
  std::uint64_t same_log_odds = 0;     // known to OctoMap, bit-identical log-odds
  [[nodiscard]] std::uint64_t known_to_either() const { return octomap_known + umbra_known - both_known; }
  [[nodiscard]] double fraction() const {
    return known_to_either() == 0 ? 1.0 : static_cast<double>(same_class) / static_cast<double>(known_to_either());
  }
};

Agreement compare(const octomap::OcTree& octree, const OccupancyMap& map) {
  Agreement a;
  const unsigned tree_depth = octree.getTreeDepth();
  for (auto it = octree.begin_leafs(), end = octree.end_leafs(); it != end; ++it) {
    const unsigned depth = tree_depth - it.getDepth();  // umbra depth (0 = finest)
    const octomap::OcTreeKey k = it.getKey();
    const bool occupied = octree.isNodeOccupied(*it);
    const float value = it->getLogOdds();
    const std::uint32_t n = 1u << depth;
    const Key base{(std::uint32_t{k[0]} >> depth) << depth, (std::uint32_t{k[1]} >> depth) << depth,
                   (std::uint32_t{k[2]} >> depth) << depth};
    for (std::uint32_t z = 0; z < n; ++z) {
      for (std::uint32_t y = 0; y < n; ++y) {
        for (std::uint32_t x = 0; x < n; ++x) {
          const float mine = map.node(Key{base.x + x, base.y + y, base.z + z}, 0).log_odds;
          const OccupancyState state = test::log_odds_thresholds(map).classify(mine);
          ++a.octomap_known;
          a.both_known += state != OccupancyState::unknown;
          a.same_class += (occupied && state == OccupancyState::occupied) || (!occupied && state == OccupancyState::free);
          a.same_log_odds += std::memcmp(&mine, &value, sizeof value) == 0;
        }
      }
    }
  }
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.state != OccupancyState::unknown) a.umbra_known += std::uint64_t{1} << (3 * leaf.depth);
  });
  return a;
}

struct Dataset {
  std::string name;
  std::vector<Scan> scans;
};

void run_comparison(const Dataset& data, double resolution, double max_range) {
  for (const bool discrete : {false, true}) {
    octomap::OcTree octree(resolution);
    OccupancyMap map(resolution);
    InsertOptions options;
    options.integrator = discrete ? IntegratorKind::discrete : IntegratorKind::simple;
    options.max_range = max_range;
    for (const Scan& scan : data.scans) {
      octomap::Pointcloud cloud;
      cloud.reserve(scan.points.size());
      for (const Vec3f& p : scan.points) cloud.push_back(p.x, p.y, p.z);
      octree.insertPointCloud(cloud, octomap::point3d(scan.origin.x, scan.origin.y, scan.origin.z), max_range, false,
                              discrete);
      map.insert_point_cloud(scan.origin, scan.points, options);
    }
    const Agreement a = compare(octree, map);
    const std::string label = data.name + (discrete ? " discrete" : " simple");
    std::printf("[ octomap  ] %s at %g m: %llu voxels known to either, %.5f%% same class, "
                "%.5f%% of OctoMap's voxels with bit-identical log-odds\n",
                label.c_str(), resolution, static_cast<unsigned long long>(a.known_to_either()), 100.0 * a.fraction(),
                100.0 * static_cast<double>(a.same_log_odds) / static_cast<double>(a.octomap_known));
    testing::Test::RecordProperty(label + " agreement", std::to_string(a.fraction()));
    EXPECT_GT(a.octomap_known, 1000u) << label;
    EXPECT_GE(a.fraction(), 0.999) << label;
    ASSERT_EQ(test::check_invariants(map), "");
  }
}

TEST(OctomapDifferential, ProceduralBuildingWithSimulatedLidar) {
  Dataset data{"procedural building", {}};
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  lidar.range_noise_stddev = 0.02;
  lidar.emit_no_return = true;  // exercises the max-range truncation
  lidar.no_return_range = 40.0;
  const auto path = sim::demo_path();
  for (std::size_t i = 0; i < path.size(); i += 3) {
    Scan scan;
    scan.origin = static_cast<Vec3f>(path[i].position);
    scan.points = sim::simulate_scan(scene, path[i], lidar);
    data.scans.push_back(std::move(scan));
  }
  run_comparison(data, 0.05, 30.0);
  run_comparison(data, 0.1, -1.0);
}

TEST(OctomapDifferential, RealLaserScanAt5cm) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/scan.dat.bz2");
  Dataset data{"scan.dat", {}};
  const auto source = open_scan_source(path);
  Scan scan;
  while (source->next(scan)) data.scans.push_back(scan);
  ASSERT_EQ(data.scans.size(), 1u);
  run_comparison(data, 0.05, 30.0);
}

TEST(OctomapDifferential, RealRegisteredScansAt10cm) {
  UMBRA_REQUIRE_SHARED_DATA(path, "3dtk/3dtk_registered.graph");
  Dataset data{"3dtk_registered.graph", {}};
  const auto source = open_scan_source(path);
  Scan scan;
  while (source->next(scan)) data.scans.push_back(scan);
  ASSERT_EQ(data.scans.size(), 3u);
  run_comparison(data, 0.1, 30.0);
}

TEST(OctomapDifferential, RaysAlongFacesAndEdgesIntoTheNeighbourVoxelAndHairThin) {
  // Scans whose rays run exactly on voxel faces and edges, end in the voxel
  // beside the origin's, or are a hair thin (offsets down to 3e-23 m, whose
  // float squared length is denormal): every voxel with bit-identical
  // log-odds, and no voxel known to umbra that OctoMap does not know.
  // Rays whose squared length underflows to 0 are left out: liboctomap
  // 1.9.7 crashes on them (it walks until its key buffer overflows; umbra
  // stops at once, tests/ray/voxel_walk_test.cpp and hostile_rays_test.cpp).
  for (const double resolution : {0.1, 0.5}) {
    const auto r = static_cast<float>(resolution);
    const std::vector<float> values = {0.0f,     -0.0f,   r,       -r,      2 * r,   -3 * r,  0.5f * r,
                                       -0.5f * r, 3e-23f, -3e-23f, 1e-22f,  -1e-20f, 1e-16f,  -1e-16f};
    std::mt19937 rng(static_cast<std::uint32_t>(resolution * 10));
    std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
    std::uniform_int_distribution<int> steps(-6, 6);
    for (const bool discrete : {false, true}) {
      for (const double max_range : {-1.0, 3.5 * resolution}) {
        octomap::OcTree octree(resolution);
        OccupancyMap map(resolution);
        InsertOptions options;
        options.integrator = discrete ? IntegratorKind::discrete : IntegratorKind::simple;
        options.max_range = max_range;
        std::size_t rays = 0;
        for (int scan = 0; scan < 40; ++scan) {
          const Vec3f origin{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
          std::vector<Vec3f> points;
          for (int i = 0; i < 50; ++i) {
            Vec3f p;
            for (std::size_t axis = 0; axis < 3; ++axis) {
              // A border value, or the origin's coordinate moved by whole voxels (faces and edges).
              p[axis] = i % 2 == 0 ? values[pick(rng)] : origin[axis] + float(steps(rng)) * r * float(i % 3 != 0);
            }
            const Vec3f d = p - origin;
            if (d.x * d.x + d.y * d.y + d.z * d.z == 0.0f) continue;  // underflows (or zero): see above
            points.push_back(p);
          }
          rays += points.size();
          octomap::Pointcloud cloud;
          for (const Vec3f& p : points) cloud.push_back(p.x, p.y, p.z);
          octree.insertPointCloud(cloud, octomap::point3d(origin.x, origin.y, origin.z), max_range, false, discrete);
          map.insert_point_cloud(origin, points, options);
        }
        const Agreement a = compare(octree, map);
        EXPECT_GT(rays, 1000u);
        EXPECT_GT(a.octomap_known, 50u);
        EXPECT_EQ(a.same_log_odds, a.octomap_known) << "resolution " << resolution << " discrete " << discrete
                                                    << " max range " << max_range;
        EXPECT_EQ(a.umbra_known, a.octomap_known) << "resolution " << resolution << " discrete " << discrete
                                                  << " max range " << max_range;
        ASSERT_EQ(test::check_invariants(map), "");
      }
    }
  }
}

}  // namespace
}  // namespace umbra
