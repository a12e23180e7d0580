// The fast integrator: exact where it must be (with enough fine steps it is
// the discrete integrator), coarse clearing that covers exactly the nodes a
// ray crosses, obstacles never cleared wholesale, and its occupied voxels
// against the simple integrator's (recall and precision, printed and
// recorded) on a procedural building and on the real scans.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "support/test_support.hpp"
#include "support/map_internals.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra {
namespace {

std::vector<std::pair<std::uint64_t, std::uint32_t>> leaves(const OccupancyMap& map) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> out;
  map.for_each_leaf([&](const Node& l) {
    out.emplace_back(morton::encode(l.key) * 32 + static_cast<std::uint64_t>(l.depth),
                     std::bit_cast<std::uint32_t>(l.log_odds));
  });
  return out;
}

std::vector<Vec3f> room_points(std::mt19937& rng, int count) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Vec3f> points;
  for (int i = 0; i < count; ++i) {
    const float a = u(rng) * 3.14159f;
    const float r = i % 7 == 0 ? 9.0f : 2.5f + 0.3f * u(rng);
    points.push_back({r * std::cos(a), r * std::sin(a), 1.2f * u(rng)});
  }
  return points;
}

TEST(FastIntegrator, WithEnoughFineStepsItIsTheDiscreteIntegrator) {
  for (const double max_range : {-1.0, 4.0}) {
    OccupancyMap discrete(0.05, 12);
    OccupancyMap fast(0.05, 12);
    std::mt19937 rng(3);
    InsertOptions d;
    d.integrator = IntegratorKind::discrete;
    d.max_range = max_range;
    InsertOptions f = d;
    f.integrator = IntegratorKind::fast;
    f.fine_steps = 1'000'000;
    for (int scan = 0; scan < 3; ++scan) {
      const std::vector<Vec3f> points = room_points(rng, 2000);
      const Vec3f origin{0.2f * scan, -0.1f, 0.05f};
      discrete.insert_point_cloud(origin, points, d);
      fast.insert_point_cloud(origin, points, f);
    }
    EXPECT_TRUE(leaves(discrete) == leaves(fast)) << "max range " << max_range;
  }
}

TEST(FastIntegrator, ClearsExactlyTheCoarseNodesARayCrosses) {
  const double resolution = 0.1;
  const int depth = 2;  // 40 cm nodes
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int trial = 0; trial < 40; ++trial) {
    OccupancyMap map(resolution, 8);  // [-12.8, 12.8)
    InsertOptions options;
    options.integrator = IntegratorKind::fast;
    options.clear_depth = depth;
    options.fine_steps = 0;
    const Vec3f origin{u(rng), u(rng), u(rng)};
    const Vec3f end{u(rng) * 3.0f, u(rng) * 3.0f, u(rng)};
    map.insert_point_cloud(origin, std::vector<Vec3f>{end}, options);
    // The ray goes to the centre of the end voxel (as for discrete).
    const Key end_key = map.key(Vec3d(end));
    const Vec3d target = map.grid().center(end_key);
    const Vec3d from(origin);
    const Vec3d d = target - from;
    const double length = d.norm();
    const std::uint32_t nodes = map.grid().keys_per_axis() >> depth;
    const double size = map.grid().node_size(depth);
    for (std::uint32_t z = 0; z < nodes; ++z) {
      for (std::uint32_t y = 0; y < nodes; ++y) {
        for (std::uint32_t x = 0; x < nodes; ++x) {
          const Key first{x << depth, y << depth, z << depth};
          const Vec3d low = map.grid().min_corner(first);
          const Aabb cube{low, low + Vec3d{size, size, size}};
          const auto part = cube.clip(from, target);
          const double inside = part ? (part->second - part->first) * length : 0.0;
          auto near = [&](std::uint32_t a, std::uint32_t b) { return a + 1 >= b && b + 1 >= a; };
          const bool is_end_node =
              (end_key.x >> depth) == x && (end_key.y >> depth) == y && (end_key.z >> depth) == z;
          const bool next_to_end_node = near(end_key.x >> depth, x) && near(end_key.y >> depth, y) &&
                                        near(end_key.z >> depth, z);
          const Node s = map.node(first, depth);
          if (is_end_node) {
            // Only the end voxel's hit; the rest of the end node stays unknown.
            EXPECT_TRUE(s.contains_unknown);
            continue;
          }
          if (next_to_end_node) {
            // Nodes next to a hit are traced voxel by voxel, never cleared whole.
            if (inside > 1e-6) {
              EXPECT_TRUE(s.contains_unknown) << "trial " << trial;
            }
            continue;
          }
          if (inside > 1e-6) {
            ASSERT_TRUE(!s.has_children && test::log_odds_thresholds(map).is_free(s.log_odds))
                << "trial " << trial << ": node " << x << "," << y << "," << z << " crossed for " << inside
                << " m but not cleared whole";
          } else if (!part) {
            ASSERT_TRUE(s.contains_unknown && !s.contains_free) << "trial " << trial << ": node " << x << "," << y
                                                                << "," << z << " not crossed but touched";
          }
        }
      }
    }
    EXPECT_EQ(map.state(target), OccupancyState::occupied);
  }
}

TEST(FastIntegrator, NeverClearsAKnownObstacleWholesale) {
  OccupancyMap map(0.1, 8);
  // An obstacle voxel next to (not on) the ray's path, inside a coarse node the ray crosses.
  const Vec3d obstacle{1.05, 0.25, 0.05};
  for (int i = 0; i < 3; ++i) map.update_hit(obstacle);
  ASSERT_EQ(map.state(obstacle), OccupancyState::occupied);
  const float before = map.log_odds(obstacle);
  InsertOptions options;
  options.integrator = IntegratorKind::fast;
  options.clear_depth = 3;  // 80 cm nodes
  options.fine_steps = 0;
  map.insert_point_cloud({0.05f, 0.05f, 0.05f}, std::vector<Vec3f>{{5.05f, 0.05f, 0.05f}}, options);
  EXPECT_EQ(map.log_odds(obstacle), before) << "the obstacle is off the ray: untouched";
  EXPECT_EQ(map.state({1.05, 0.05, 0.05}), OccupancyState::free) << "voxels on the ray in that node are cleared";
  EXPECT_EQ(map.state({1.05, 0.45, 0.05}), OccupancyState::unknown) << "the node was not cleared wholesale";
  EXPECT_EQ(map.state({3.05, 0.45, 0.05}), OccupancyState::free) << "obstacle-free nodes are cleared whole";
}

struct Comparison {
  std::size_t simple_occupied = 0;
  std::size_t fast_occupied = 0;
  std::size_t both = 0;
  std::size_t occupied_made_free = 0;  // occupied in simple, free in fast
  [[nodiscard]] double recall() const { return static_cast<double>(both) / static_cast<double>(simple_occupied); }
  [[nodiscard]] double precision() const { return static_cast<double>(both) / static_cast<double>(fast_occupied); }
};

Comparison compare(const OccupancyMap& simple, const OccupancyMap& fast) {
  Comparison c;
  simple.for_each_leaf([&](const Node& l) {
    if (l.state != OccupancyState::occupied) return;
    // A pruned node holds equal voxels: compare each of them.
    const std::uint32_t n = 1u << l.depth;
    for (std::uint32_t z = 0; z < n; ++z) {
      for (std::uint32_t y = 0; y < n; ++y) {
        for (std::uint32_t x = 0; x < n; ++x) {
          ++c.simple_occupied;
          const Key voxel{l.key.x + x, l.key.y + y, l.key.z + z};
          const OccupancyState other = test::log_odds_thresholds(fast).classify(fast.node(voxel).log_odds);
          c.both += other == OccupancyState::occupied;
          c.occupied_made_free += other == OccupancyState::free;
        }
      }
    }
  });
  fast.for_each_leaf([&](const Node& l) {
    if (l.state == OccupancyState::occupied) c.fast_occupied += std::size_t{1} << (3 * l.depth);
  });
  return c;
}

OccupancyMap build(const std::vector<Scan>& scans, double resolution, double max_range, IntegratorKind kind,
                   int fine_steps) {
  OccupancyMap map(resolution);
  InsertOptions options;
  options.integrator = kind;
  options.fine_steps = fine_steps;
  options.max_range = max_range;
  for (const Scan& scan : scans) map.insert_point_cloud(scan.origin, scan.points, options);
  return map;
}

/// Voxels one to three voxels behind the scan's occupied end points, along
/// their rays, that are free in `fast` but not in `exact`.
std::size_t free_behind_surfaces(const Scan& scan, const OccupancyMap& exact, const OccupancyMap& fast,
                                 double max_range, std::size_t& checked) {
  std::size_t extra = 0;
  const double resolution = exact.resolution();
  for (const Vec3f& point : scan.points) {
    const Vec3d p(point);
    if (!exact.grid().key_checked(p) || exact.state(p) != OccupancyState::occupied) continue;
    const Vec3d d = p - Vec3d(scan.origin);
    const double range = d.norm();
    if (max_range > 0 && range > max_range) continue;
    for (int step = 1; step <= 3; ++step) {
      const Vec3d behind = p + d * (step * resolution / range);
      if (!exact.grid().key_checked(behind)) break;
      ++checked;
      extra += fast.state(behind) == OccupancyState::free && exact.state(behind) != OccupancyState::free;
    }
  }
  return extra;
}

/// The fast integrator (n = 2 and n = 0, clear depth at 16 cm) against its
/// exact counterpart, the discrete integrator, and against the simple one:
/// recall and precision of the occupied voxels (printed and recorded; the
/// goal is recall >= 99% and precision >= 98%), and no free space behind the
/// surfaces of a scan beyond what the discrete integrator frees there.
void check_fast_integrator(const std::string& name, const std::vector<Scan>& scans, double resolution,
                           double max_range) {
  const OccupancyMap simple = build(scans, resolution, max_range, IntegratorKind::simple, 0);
  const OccupancyMap discrete = build(scans, resolution, max_range, IntegratorKind::discrete, 0);
  const Comparison baseline = compare(simple, discrete);
  std::printf("[ fast     ] %s at %g m: discrete vs simple: recall %.4f%%, precision %.4f%%\n", name.c_str(),
              resolution, 100.0 * baseline.recall(), 100.0 * baseline.precision());
  for (const int fine_steps : {2, 0}) {
    const OccupancyMap fast = build(scans, resolution, max_range, IntegratorKind::fast, fine_steps);
    ASSERT_EQ(test::check_invariants(fast), "");
    const Comparison to_simple = compare(simple, fast);
    const Comparison to_discrete = compare(discrete, fast);
    const std::string label = name + " n=" + std::to_string(fine_steps);
    std::printf("[ fast     ] %s: vs simple: recall %.4f%%, precision %.4f%%; vs discrete: recall %.4f%%, "
                "precision %.4f%% (%zu occupied in discrete, %zu in fast, %zu made free)\n",
                label.c_str(), 100.0 * to_simple.recall(), 100.0 * to_simple.precision(), 100.0 * to_discrete.recall(),
                100.0 * to_discrete.precision(), to_discrete.simple_occupied, to_discrete.fast_occupied,
                to_discrete.occupied_made_free);
    testing::Test::RecordProperty(label + " recall vs simple", std::to_string(to_simple.recall()));
    testing::Test::RecordProperty(label + " precision vs simple", std::to_string(to_simple.precision()));
    testing::Test::RecordProperty(label + " recall vs discrete", std::to_string(to_discrete.recall()));
    testing::Test::RecordProperty(label + " precision vs discrete", std::to_string(to_discrete.precision()));
    EXPECT_GT(to_discrete.simple_occupied, 1000u);
    EXPECT_GE(to_discrete.recall(), 0.99) << label;
    EXPECT_GE(to_discrete.precision(), 0.98) << label;
    EXPECT_GE(to_simple.recall(), 0.99) << label;
    EXPECT_GE(to_simple.precision(), 0.98) << label;
  }
  // Behind surfaces: one scan at a time, so "behind" has one meaning.
  for (const int fine_steps : {2, 0}) {
    std::size_t checked = 0;
    std::size_t extra = 0;
    for (const Scan& scan : scans) {
      const std::vector<Scan> one{scan};
      extra += free_behind_surfaces(scan, build(one, resolution, max_range, IntegratorKind::discrete, 0),
                                    build(one, resolution, max_range, IntegratorKind::fast, fine_steps), max_range,
                                    checked);
    }
    std::printf("[ fast     ] %s n=%d: %zu of %zu voxels behind surfaces free in fast but not in discrete\n",
                name.c_str(), fine_steps, extra, checked);
    EXPECT_GT(checked, 100u);
    // Tracing a node from where the ray enters it rounds a little
    // differently from tracing the whole ray, so a few grazed voxels differ;
    // clearing coarse nodes behind surfaces would show as thousands.
    // (measured: 1-2 in 10,000; without keeping the nodes next to hits fine, 7-22 in 1,000).
    EXPECT_LE(extra * 1'000, checked) << name << " n=" << fine_steps;
  }
}

TEST(FastIntegrator, AgreesWithTheSimpleIntegratorOnTheProceduralBuilding) {
  const sim::Scene scene = sim::make_demo_scene();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  lidar.range_noise_stddev = 0.01;
  std::vector<Scan> scans;
  const auto path = sim::demo_path();
  for (std::size_t i = 0; i < path.size(); i += 2) {
    Scan scan;
    scan.origin = static_cast<Vec3f>(path[i].position);
    scan.points = sim::simulate_scan(scene, path[i], lidar);
    scans.push_back(std::move(scan));
  }
  check_fast_integrator("procedural building", scans, 0.05, 30.0);
}

using test::read_all;

TEST(FastIntegrator, AgreesWithTheSimpleIntegratorOnScanDat) {
  UMBRA_REQUIRE_SHARED_DATA(path, "octomap/scan.dat.bz2");
  check_fast_integrator("scan.dat", read_all(path), 0.05, 30.0);
}

TEST(FastIntegrator, AgreesWithTheSimpleIntegratorOn3dtk) {
  UMBRA_REQUIRE_SHARED_DATA(path, "3dtk/3dtk_registered.graph");
  check_fast_integrator("3dtk", read_all(path), 0.05, 30.0);
}

}  // namespace
}  // namespace umbra
