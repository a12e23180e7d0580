// Rays that broke the integrators (issue 21): a point a hair's breadth from
// the sensor across the voxel border at 0, whose float squared length
// underflows (OctoMap's normalisation then divides by zero; umbra crashed
// or freed a column of voxels to the map's edge), and a point so far away
// that the float squared length overflows. Checked against the dense-grid
// reference (simple, discrete) and, for every integrator, against what such
// a ray may touch at all: the voxels around the origin.
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "support/map_internals.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

/// Coordinates within 1e-16 of the border at 0 (tiny, denormal, zero, both signs).
std::vector<float> hair_values() {
  std::vector<float> values = {0.0f, -0.0f};
  for (const float v : {1e-23f, 1e-29f, 2.5e-23f, 3e-23f, 1e-22f, 1e-20f, 1e-16f, 1e-40f,
                        std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min()}) {
    values.push_back(v);
    values.push_back(-v);
  }
  return values;
}

/// Adds to `changed` the finest voxels of the depth-`depth` node at `key`
/// whose log-odds in `b` differ from `value`, the log-odds of every voxel of
/// that node in `a` (a leaf there).
void differing_voxels(const OccupancyMap& b, Key key, int depth, float value, std::set<std::uint64_t>& changed) {
  const Node other = b.node(key, depth);
  if (!other.has_children) {
    if (other.log_odds == value) return;
    const std::uint32_t n = 1u << depth;
    for (std::uint32_t i = 0; i < n * n * n; ++i) {
      changed.insert(morton::encode({key.x + i % n, key.y + i / n % n, key.z + i / (n * n)}));
    }
    return;
  }
  const std::uint32_t half = 1u << (depth - 1);
  for (std::uint32_t i = 0; i < 8; ++i) {
    differing_voxels(b, {key.x + (i & 1) * half, key.y + (i >> 1 & 1) * half, key.z + (i >> 2) * half}, depth - 1,
                     value, changed);
  }
}

/// The finest voxels whose log-odds differ between two maps of one grid.
std::set<std::uint64_t> changed_voxels(const OccupancyMap& before, const OccupancyMap& after) {
  std::set<std::uint64_t> changed;
  before.for_each_leaf([&](const Node& leaf) { differing_voxels(after, leaf.key, leaf.depth, leaf.log_odds, changed); });
  after.for_each_leaf([&](const Node& leaf) { differing_voxels(before, leaf.key, leaf.depth, leaf.log_odds, changed); });
  return changed;
}

/// A ring of points at 2 m around the origin: a map with free, occupied and unknown space.
std::vector<Vec3f> ring(int count) {
  std::vector<Vec3f> points;
  for (int i = 0; i < count; ++i) {
    const double a = 2.0 * M_PI * (i + 0.37) / count;
    points.push_back({static_cast<float>(2.0 * std::cos(a)), static_cast<float>(2.0 * std::sin(a)),
                      static_cast<float>(0.3 * std::sin(3 * a))});
  }
  return points;
}

std::string name_of(const InsertOptions& o) {
  return std::string(to_string(o.integrator)) + " clear depth " + std::to_string(o.clear_depth) + " fine steps " +
         std::to_string(o.fine_steps) + " threads " + std::to_string(o.threads) + " max range " +
         std::to_string(o.max_range);
}

std::vector<InsertOptions> every_integrator() {
  std::vector<InsertOptions> all;
  for (const IntegratorKind kind : {IntegratorKind::simple, IntegratorKind::discrete}) {
    InsertOptions o;
    o.integrator = kind;
    all.push_back(o);
  }
  for (const int clear_depth : {1, 2, 5}) {  // 5: large nodes, split down to depth 1
    for (const int fine_steps : {0, 1, 2}) {
      InsertOptions o;
      o.integrator = IntegratorKind::fast;
      o.clear_depth = clear_depth;
      o.fine_steps = fine_steps;
      all.push_back(o);
    }
  }
  return all;
}

TEST(HostileRays, APointBesideTheSensorAcrossTheBorderAtZeroGivesItsHitAndFreesTheSensorsVoxel) {
  // The reported inputs: sensor at the origin, one point (-1e-23, 1e-23, 0)
  // or (-1e-29, 1e-29, 0), in a default map (0.1 m, 16 levels), alone and
  // after an ordinary scan. As OctoMap's rule for a ray into the
  // neighbouring voxel: the sensor's voxel gets a miss, the point's a hit.
  for (const Vec3f point : {Vec3f{-1e-23f, 1e-23f, 0.0f}, Vec3f{-1e-29f, 1e-29f, 0.0f}}) {
    for (InsertOptions options : every_integrator()) {
      for (const unsigned threads : {1u, 2u}) {
        options.threads = threads;
        for (const bool after_a_scan : {false, true}) {
          OccupancyMap map(0.1);
          if (after_a_scan) map.insert_point_cloud({0.5f, 0.5f, 0.5f}, ring(500), options);
          const OccupancyMap before = map;
          const InsertStats stats = map.insert_point_cloud({0, 0, 0}, std::vector<Vec3f>{point}, options);
          ASSERT_EQ(test::check_invariants(map), "") << name_of(options);
          EXPECT_EQ(stats.rays, 1u);
          const std::set<std::uint64_t> changed = changed_voxels(before, map);
          const std::uint64_t sensor = morton::encode(map.key({0, 0, 0}));
          const std::uint64_t hit = morton::encode(map.key(Vec3d(point)));
          EXPECT_EQ(changed, (std::set<std::uint64_t>{sensor, hit})) << name_of(options) << " after a scan "
                                                                      << after_a_scan;
          EXPECT_EQ(map.state(Vec3d(point)), OccupancyState::occupied) << name_of(options);
          EXPECT_LT(map.log_odds({0.05, 0.05, 0.05}), before.log_odds({0.05, 0.05, 0.05})) << name_of(options);
        }
      }
    }
  }
}

TEST(HostileRays, HairThinRaysChangeOnlyTheVoxelsAroundTheSensor) {
  // Sensors and points whose coordinates all lie within 1e-16 of the border
  // at 0: every ray ends in one of the eight voxels around the origin and
  // may change nothing else (the fast integrator: nothing outside the
  // coarse nodes around them), whatever the integrator, box and range.
  const std::vector<float> values = hair_values();
  std::mt19937 rng(21);
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  const auto hair = [&] { return Vec3f{values[pick(rng)], values[pick(rng)], values[pick(rng)]}; };
  const std::vector<std::optional<Aabb>> boxes = {std::nullopt, Aabb{{-1, -1, -1}, {1, 1, 1}},
                                                  Aabb{{0, -1, -1}, {1, 1, 0}}};  // two faces on the border
  std::size_t changed_total = 0;
  for (const double resolution : {0.1, 0.5}) {
    for (const std::optional<Aabb>& box : boxes) {
      for (InsertOptions options : every_integrator()) {
        for (const double max_range : {-1.0, 1e-30, 2.0}) {
          options.max_range = max_range;
          OccupancyMap map(resolution, 8);  // 256 voxels a side: clear depth 5 nodes are 32
          map.insert_point_cloud({0.3f, -0.2f, 0.1f}, ring(300), options);
          map.set_bounding_box(box);
          const OccupancyMap before = map;
          std::vector<Vec3f> points;
          for (int i = 0; i < 60; ++i) points.push_back(hair());
          map.insert_point_cloud(hair(), points, options);
          ASSERT_EQ(test::check_invariants(map), "") << name_of(options);
          const std::set<std::uint64_t> changed = changed_voxels(before, map);
          changed_total += changed.size();
          // The fast integrator clears whole the coarse nodes a ray crosses
          // (a ray with no hit, cut at max_range, clears the sensor's node).
          const int coarse = options.integrator == IntegratorKind::fast ? options.clear_depth : 0;
          const std::uint32_t o = map.grid().key_offset();
          for (const std::uint64_t code : changed) {
            const Key k = morton::decode(code);
            for (int axis = 0; axis < 3; ++axis) {
              ASSERT_TRUE(k[axis] >> coarse == o >> coarse || k[axis] >> coarse == (o - 1) >> coarse)
                  << name_of(options) << " resolution " << resolution << ": voxel " << k.x << "," << k.y << ","
                  << k.z << " changed";
            }
            if (box) {  // the voxels the box covers (its faces' voxels included)
              const Key low = map.key(box->min);
              const Key high = map.key(box->max);
              ASSERT_TRUE(k.x >= low.x && k.y >= low.y && k.z >= low.z && k.x <= high.x && k.y <= high.y &&
                          k.z <= high.z)
                  << name_of(options);
            }
          }
        }
      }
    }
  }
  EXPECT_GT(changed_total, 1000u) << "the hair-thin scans must change the voxels around the sensor";
}

TEST(HostileRays, HairThinScansMatchTheDenseGrid) {
  // The simple and discrete integrators, voxel for voxel, against the
  // reference: hair-thin rays, ordinary rays and rays along faces from
  // sensors on the border at 0.
  const std::vector<float> values = hair_values();
  const SensorModel sensor;
  for (const double resolution : {0.1, 0.5}) {
    for (const IntegratorKind kind : {IntegratorKind::simple, IntegratorKind::discrete}) {
      for (const double max_range : {-1.0, 1.0}) {
        std::mt19937 rng(7);
        std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
        std::uniform_real_distribution<float> anywhere(-3.0f, 3.0f);
        OccupancyMap map(resolution, 6, sensor);
        test::DenseGrid oracle(resolution, 6, sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds());
        InsertOptions options;
        options.integrator = kind;
        options.max_range = max_range;
        for (int scan = 0; scan < 8; ++scan) {
          const Vec3f origin{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
          std::vector<Vec3f> points;
          for (int i = 0; i < 300; ++i) {
            Vec3f p{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
            if (i % 3 == 1) p[i % 2] = anywhere(rng);   // along a face through the origin's border
            if (i % 3 == 2) p = {anywhere(rng), anywhere(rng), anywhere(rng)};
            points.push_back(p);
          }
          map.insert_point_cloud(origin, points, options);
          oracle.insert_scan(origin, points, {kind == IntegratorKind::discrete, max_range}, sensor.hit_log_odds(),
                             sensor.miss_log_odds());
          ASSERT_EQ(test::check_invariants(map), "");
        }
        for (std::uint32_t z = 0; z < oracle.size(); ++z) {
          for (std::uint32_t y = 0; y < oracle.size(); ++y) {
            for (std::uint32_t x = 0; x < oracle.size(); ++x) {
              ASSERT_EQ(map.node(Key{x, y, z}).log_odds, oracle.at(Key{x, y, z}))
                  << to_string(kind) << " resolution " << resolution << " max range " << max_range << " voxel "
                  << x << "," << y << "," << z;
            }
          }
        }
      }
    }
  }
}

TEST(HostileRays, APointBeyondFloatsSquaredRangeIsCutAtMaxRangeAlongItsDirection) {
  // (3e19, 1e19, 0): its float squared length overflows. OctoMap's
  // normalised direction is then zero and the ray updates nothing; umbra
  // cuts it at max_range along the point's direction like any far point.
  // (The simple integrator: the discrete and fast ones drop points outside
  // the map, as they need the point's voxel.)
  const SensorModel sensor;
  OccupancyMap map(0.1, 7, sensor);
  test::DenseGrid oracle(0.1, 7, sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds());
  InsertOptions options;
  options.integrator = IntegratorKind::simple;
  options.max_range = 2.0;
  const Vec3f origin{0.05f, 0.05f, 0.05f};
  const std::vector<Vec3f> points = {{3e19f, 1e19f, 0.0f}, {-2e30f, 0.0f, 1e30f}, {0.0f, -3e38f, 0.0f}};
  const InsertStats stats = map.insert_point_cloud(origin, points, options);
  EXPECT_EQ(stats.truncated, 3u);
  ASSERT_EQ(test::check_invariants(map), "");
  for (const Vec3f& p : points) {
    const Vec3d direction = Vec3d(p) / Vec3d(p).norm();
    EXPECT_EQ(map.state(Vec3d(origin) + direction * 1.5), OccupancyState::free) << p.x << "," << p.y << "," << p.z;
    EXPECT_EQ(map.state(Vec3d(origin) + direction * 2.3), OccupancyState::unknown) << p.x << "," << p.y << "," << p.z;
  }
  oracle.insert_scan(origin, points, {false, options.max_range}, sensor.hit_log_odds(), sensor.miss_log_odds());
  for (std::uint32_t z = 0; z < oracle.size(); ++z) {
    for (std::uint32_t y = 0; y < oracle.size(); ++y) {
      for (std::uint32_t x = 0; x < oracle.size(); ++x) {
        ASSERT_EQ(map.node(Key{x, y, z}).log_odds, oracle.at(Key{x, y, z})) << x << "," << y << "," << z;
      }
    }
  }
}

}  // namespace
}  // namespace umbra
