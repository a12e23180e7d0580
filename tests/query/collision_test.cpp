// Collision checks, line checks and ray casts against brute force over the
// dense voxel values of random maps (several depths, automatic pruning on
// and off, thresholds changed at run time, unknown blocking or not, checks
// at depth 0 and coarser).
//
// Brute force: a region blocks when some finest voxel whose cube meets the
// shape blocks (occupied, or unknown when unknown blocks); at depth d, when
// some depth-d node meeting the shape holds a blocking voxel. A segment's
// voxels come from the test grid's own copy of OctoMap's ray walk; a ray
// cast's from a plain copy of OctoMap's castRay stepping written here.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "support/map_internals.hpp"
#include "support/query_oracle.hpp"
#include "support/shape_oracle.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

using test::clamp_distance_squared;
using test::Cube;
using test::meets;

/// The brute-force world: dense values, and which depth-d nodes block.
class Oracle {
 public:
  Oracle(const OccupancyMap& map, bool unknown_blocks)
      : map_(map), dense_(map), t_(LogOddsThresholds::from(map.thresholds())), unknown_blocks_(unknown_blocks) {
    // blocking_[d][node]: any blocking voxel in the depth-d node, from the voxels up.
    const std::uint32_t size = map.grid().keys_per_axis();
    blocking_.emplace_back(std::size_t{size} * size * size);
    for (std::uint32_t z = 0; z < size; ++z) {
      for (std::uint32_t y = 0; y < size; ++y) {
        for (std::uint32_t x = 0; x < size; ++x) blocking_[0][(std::size_t{z} * size + y) * size + x] = voxel_blocks({x, y, z});
      }
    }
    for (int d = 1; d <= map.depth_levels(); ++d) {
      const std::uint32_t n = size >> d;
      const std::uint32_t below = n * 2;
      std::vector<bool> level(std::size_t{n} * n * n, false);
      for (std::uint32_t z = 0; z < n; ++z) {
        for (std::uint32_t y = 0; y < n; ++y) {
          for (std::uint32_t x = 0; x < n; ++x) {
            bool any = false;
            for (unsigned i = 0; i < 8; ++i) {
              const std::uint32_t cx = 2 * x + (i & 1), cy = 2 * y + (i >> 1 & 1), cz = 2 * z + (i >> 2 & 1);
              any = any || blocking_[static_cast<std::size_t>(d - 1)][(std::size_t{cz} * below + cy) * below + cx];
            }
            level[(std::size_t{z} * n + y) * n + x] = any;
          }
        }
      }
      blocking_.push_back(std::move(level));
    }
  }

  [[nodiscard]] bool voxel_blocks(Key k) const {
    const float v = dense_.at(k);
    return t_.is_occupied(v) || (unknown_blocks_ && t_.is_unknown(v));
  }
  /// Does the depth-`depth` node containing finest key `k` hold a blocking voxel?
  [[nodiscard]] bool node_blocks(Key k, int depth) const {
    const Key base = k.at_depth(depth);
    const std::uint32_t n = map_.grid().keys_per_axis() >> depth;
    return blocking_[static_cast<std::size_t>(depth)][(std::size_t{base.z} * n + base.y) * n + base.x];
  }
  [[nodiscard]] Cube cube(Key k, int depth) const {
    const Vec3d low = map_.grid().min_corner(k, depth);
    const double size = map_.grid().node_size(depth);
    return {low, low + Vec3d{size, size, size}};
  }
  /// Is the region free at `depth` by brute force?
  template <typename Shape>
  [[nodiscard]] bool region_free(const Shape& shape, int depth) const {
    const std::uint32_t n = map_.grid().keys_per_axis() >> depth;
    for (std::uint32_t z = 0; z < n; ++z) {
      for (std::uint32_t y = 0; y < n; ++y) {
        for (std::uint32_t x = 0; x < n; ++x) {
          const Key k{x << depth, y << depth, z << depth};
          if (meets(shape, cube(k, depth)) && node_blocks(k, depth)) return false;
        }
      }
    }
    return true;
  }
  [[nodiscard]] const test::DenseValues& dense() const { return dense_; }

 private:
  const OccupancyMap& map_;
  test::DenseValues dense_;
  LogOddsThresholds t_;
  bool unknown_blocks_;
  std::vector<std::vector<bool>> blocking_;  // [depth][node index]
};

bool contains(const Node& node, Key k) {
  const std::uint32_t edge = 1u << node.depth;
  for (int a = 0; a < 3; ++a) {
    if (k[a] < node.key[a] || k[a] >= node.key[a] + edge) return false;
  }
  return true;
}

/// OctoMap's castRay stepping, written out plainly: the keys from the origin's voxel on, with the
/// ray parameter at which each is entered, until the map's edge or `limit` steps.
std::vector<std::pair<Key, double>> cast_keys(const Grid& grid, Vec3f origin, Vec3f direction, std::size_t limit) {
  const float squared = direction.x * direction.x + direction.y * direction.y + direction.z * direction.z;
  const auto length = static_cast<float>(std::sqrt(static_cast<double>(squared)));
  const float d[3] = {direction.x / length, direction.y / length, direction.z / length};
  const Key start = grid.key(Vec3d(origin));
  std::int64_t key[3] = {start.x, start.y, start.z};
  int step[3];
  double t_max[3];
  double t_delta[3];
  for (int i = 0; i < 3; ++i) {
    step[i] = d[i] > 0 ? 1 : (d[i] < 0 ? -1 : 0);
    if (step[i] != 0) {
      const double border = grid.axis_center(static_cast<std::uint32_t>(key[i])) + double(step[i] * grid.resolution() * 0.5);
      t_max[i] = (border - origin[i]) / d[i];
      t_delta[i] = grid.resolution() / std::fabs(d[i]);
    } else {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  std::vector<std::pair<Key, double>> out{{start, 0.0}};
  while (out.size() < limit) {
    int dim = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    const std::int64_t next = key[dim] + step[dim];
    if (next < 0 || next >= std::int64_t{grid.keys_per_axis()}) break;
    const double entered = t_max[dim];
    key[dim] = next;
    t_max[dim] += t_delta[dim];
    out.push_back({Key{std::uint32_t(key[0]), std::uint32_t(key[1]), std::uint32_t(key[2])}, entered});
  }
  return out;
}

struct Config {
  int depth_levels;
  bool auto_prune;
  unsigned seed;
};

class Collision : public testing::TestWithParam<Config> {};

TEST_P(Collision, RegionsSegmentsAndRaysAgreeWithBruteForce) {
  const Config c = GetParam();
  test::RandomMapSpec spec;
  spec.depth_levels = c.depth_levels;
  spec.auto_prune = c.auto_prune;
  spec.seed = c.seed;
  spec.block_fill = 0.6;
  OccupancyMap map = test::random_map(spec);
  std::mt19937 rng(c.seed + 100);
  const double h = map.grid().half_extent() * 0.97;
  std::uniform_real_distribution<double> coordinate(-h, h);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto point = [&] { return Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)}; };
  // Shapes of bounded size that stay inside the map.
  auto inside = [&](double r) {
    const double m = h - r;
    std::uniform_real_distribution<double> u(-m, m);
    return Vec3d{u(rng), u(rng), u(rng)};
  };

  std::size_t free_found = 0;
  std::size_t blocked_found = 0;
  for (const Thresholds thresholds : {Thresholds{0.5, 0.5}, Thresholds{0.62, 0.4}}) {
    map.set_thresholds(thresholds);
    for (const bool unknown_is_free : {false, true}) {
      const Oracle oracle(map, !unknown_is_free);
      for (const int depth : {0, 1, 2}) {
        const CollisionOptions options{unknown_is_free, depth};
        const std::string where = "thresholds " + std::to_string(thresholds.free) + "/" +
                                  std::to_string(thresholds.occupied) + " unknown_is_free " +
                                  std::to_string(unknown_is_free) + " depth " + std::to_string(depth);
        auto check = [&](const auto& shape, const char* kind) {
          SCOPED_TRACE(where + " " + kind);
          const CollisionResult got = map.is_free(shape, options);
          const bool want = oracle.region_free(shape, depth);
          ASSERT_EQ(got.free, want);
          (want ? free_found : blocked_found) += 1;
          if (!got.free) {
            ASSERT_TRUE(got.blocking.has_value());
            const Node& b = *got.blocking;
            EXPECT_GE(b.depth, depth);
            EXPECT_TRUE(meets(shape, Cube{b.min_corner(), b.max_corner()})) << "the blocking node misses the shape";
            EXPECT_TRUE(oracle.node_blocks(b.key, b.depth)) << "the reported node holds nothing blocking";
          } else {
            EXPECT_FALSE(got.blocking.has_value());
          }
          if (depth > 0 && got.free) {
            EXPECT_TRUE(map.is_free(shape, {unknown_is_free, 0}).free) << "coarse free but fine blocked";
          }
        };
        // Sizes relative to the map, small enough that many regions are free.
        auto size = [&](double most) { return h * most * unit(rng); };
        for (int i = 0; i < 25; ++i) {
          const double r = 0.02 * h + size(0.3);
          check(Sphere{inside(r), r}, "sphere");
          const Vec3d a = inside(0.2 * h);
          const Vec3d extent{size(0.2), size(0.2), size(0.2)};
          check(Aabb{a - extent, a + extent}, "box");
          std::normal_distribution<double> n;
          check(OrientedBox::from_quaternion(inside(0.35 * h), {size(0.2), size(0.2), size(0.2)}, n(rng), n(rng), n(rng),
                                             n(rng)),
                "oriented box");
          const double cr = size(0.15);
          check(Capsule{inside(cr), inside(cr), cr}, "capsule");
        }
        // Segments: the first blocking node along the walk.
        for (int i = 0; i < 40; ++i) {
          SCOPED_TRACE(where + " segment " + std::to_string(i));
          const Segment s{point(), point()};
          test::DenseGrid walker(map.resolution(), map.depth_levels(), -2.0f, 3.5f);
          std::vector<Key> keys;
          ASSERT_TRUE(walker.ray_keys(Vec3f(s.from), Vec3f(s.to), keys));
          keys.push_back(map.grid().key(Vec3d(Vec3f(s.to))));
          std::optional<Key> first;
          for (const Key& k : keys) {
            if (oracle.node_blocks(k, depth)) {
              first = k;
              break;
            }
          }
          const CollisionResult got = map.is_free(s, options);
          ASSERT_EQ(got.free, !first.has_value());
          if (first) {
            EXPECT_TRUE(contains(*got.blocking, *first)) << "not the first blocking node along the segment";
            EXPECT_GE(got.blocking->depth, depth);
          }
        }
        // Ray casts: the first occupied (or unknown) node, with its entry distance.
        for (int i = 0; i < 40; ++i) {
          SCOPED_TRACE(where + " ray " + std::to_string(i));
          const Vec3d origin = point();
          const Vec3d direction{coordinate(rng), coordinate(rng), coordinate(rng)};
          const double max_range = i % 3 == 0 ? -1.0 : 3.0 * unit(rng);
          const Oracle& stops = oracle;  // unknown stops the ray exactly when it blocks here
          const RayHit got = map.cast_ray(origin, direction, {max_range, !unknown_is_free, depth});
          std::optional<std::pair<Key, double>> want;
          for (const auto& [k, entered] : cast_keys(map.grid(), Vec3f(origin), Vec3f(direction), 1u << 20)) {
            if (max_range > 0 && entered > max_range) break;
            if (stops.node_blocks(k, depth)) {
              want = {k, entered};
              break;
            }
          }
          ASSERT_EQ(got.hit, want.has_value());
          if (want) {
            EXPECT_TRUE(contains(got.node, want->first));
            EXPECT_GE(got.node.depth, depth);
            EXPECT_DOUBLE_EQ(got.distance, want->second);
          }
        }
      }
    }
  }
  // Both answers must have occurred, or the test proves little.
  EXPECT_GT(free_found, 10u);
  EXPECT_GT(blocked_found, 10u);
}

INSTANTIATE_TEST_SUITE_P(Maps, Collision,
                         testing::Values(Config{4, true, 5}, Config{5, false, 6}, Config{5, true, 7}),
                         [](const testing::TestParamInfo<Config>& param_info) {
                           return "levels" + std::to_string(param_info.param.depth_levels) +
                                  (param_info.param.auto_prune ? "_pruned" : "_unpruned");
                         });

TEST(Collision, BadShapesAndShapesOutsideTheMapAreRefused) {
  const OccupancyMap map(0.1, 5);  // spans [-1.6, 1.6)
  EXPECT_THROW((void)map.is_free(Sphere{{0, 0, 0}, -0.1}), std::invalid_argument);
  EXPECT_THROW((void)map.is_free(Sphere{{1.5, 0, 0}, 0.3}), std::out_of_range);
  EXPECT_THROW((void)map.is_free(Segment{{0, 0, 0}, {2, 0, 0}}), std::out_of_range);
  EXPECT_THROW((void)map.is_free(Sphere{{0, 0, 0}, 0.1}, {false, 6}), std::out_of_range);
  EXPECT_THROW((void)map.cast_ray({0, 0, 0}, {0, 0, 0}), std::invalid_argument);
  EXPECT_THROW((void)map.cast_ray({5, 0, 0}, {1, 0, 0}), std::out_of_range);
  const std::vector<Sphere> spheres(3, Sphere{{0, 0, 0}, 0.1});
  std::vector<std::uint8_t> answers(2);
  EXPECT_THROW(map.is_free(std::span<const Sphere>(spheres), std::span<std::uint8_t>(answers)), std::invalid_argument);
}

// Directions whose float form overflowed or vanished (found by the query-line
// fuzzer: "0.55 0.25 0.13 1 0 5.5e57" never returned): they cast like their
// ordinary-sized multiples, with and without a range.
TEST(Collision, HugeAndTinyRayDirectionsCastLikeOrdinaryOnes) {
  OccupancyMap map(0.1, 6);  // spans [-3.2, 3.2)
  std::vector<Vec3f> wall;
  for (float y = -1.0f; y <= 1.0f; y += 0.05f) {
    for (float z = -1.0f; z <= 1.0f; z += 0.05f) wall.push_back({2.0f, y, z});
  }
  map.insert_point_cloud({0.05f, 0.05f, 0.05f}, wall);
  const Vec3d origin{0.05, 0.05, 0.05};
  for (const Vec3d unit : {Vec3d{1, 0, 0}, Vec3d{1, 0.3, -0.2}, Vec3d{0, 0, 1}, Vec3d{-1, 0, 1e-3}}) {
    for (const double range : {-1.0, 2.5}) {
      const RayHit expected = map.cast_ray(origin, unit, {range, false, 0});
      for (const double scale : {1e20, 1e57, 1e300, 1e-20, 1e-300}) {
        const RayHit got = map.cast_ray(origin, unit * scale, {range, false, 0});
        EXPECT_EQ(got.hit, expected.hit) << scale;
        EXPECT_EQ(got.node.center, expected.node.center) << scale;
        EXPECT_EQ(got.distance, expected.distance) << scale;
      }
    }
  }
  // A component beyond float range beside an ordinary one: along that axis.
  const RayHit along_x = map.cast_ray(origin, {5.5e57, 1, 0});
  EXPECT_TRUE(along_x.hit);
  EXPECT_EQ(along_x.node.center, map.cast_ray(origin, {1, 0, 0}).node.center);
  EXPECT_FALSE(map.cast_ray(origin, {1, 0, 5.5e57}).hit);  // straight up: nothing there, and it returns
  EXPECT_EQ(map.cast_ray(origin, {1e-320, 0, 0}).node.center, along_x.node.center);  // subnormal: still a ray
}

TEST(Collision, HairThinSegmentsAndSegmentsAlongFacesStopAtTheFirstBlockingVoxelOfTheReferenceWalk) {
  // Segments between points a hair's breadth from the border at 0 (tiny,
  // denormal, zero, both signs: the float squared length of many
  // underflows, and the walk's direction was infinite / NaN, so the check
  // never ended), segments along voxel faces and edges, and segments into
  // the voxel beside their start, in a map whose voxels around the origin
  // are occupied, free or unknown: the answer is the first blocking voxel
  // of the reference walk (the test DenseGrid's computeRayKeys, with its end voxel).
  const double resolution = 0.1;
  OccupancyMap map(resolution, 6);
  std::mt19937 rng(21);
  const std::uint32_t o = map.grid().key_offset();
  for (std::uint32_t z = o - 3; z <= o + 2; ++z) {
    for (std::uint32_t y = o - 3; y <= o + 2; ++y) {
      for (std::uint32_t x = o - 3; x <= o + 2; ++x) {
        const unsigned kind = rng() % 3;  // unknown, free, occupied
        if (kind != 0) map.set_log_odds(Key{x, y, z}, kind == 1 ? -2.0f : 2.0f);
      }
    }
  }
  std::vector<float> values = {0.0f, -0.0f, 0.1f, -0.1f, 0.2f, -0.05f};
  for (const float v : {1e-23f, 1e-29f, 3e-23f, 1e-20f, 1e-40f, std::numeric_limits<float>::denorm_min()}) {
    values.push_back(v);
    values.push_back(-v);
  }
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  const test::DenseGrid walker(resolution, 6, -2.0f, 3.5f);
  const test::DenseValues dense(map);
  const LogOddsThresholds& t = test::log_odds_thresholds(map);
  std::size_t blocked = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3f from{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
    const Vec3f to = i == 0 ? Vec3f{-1e-23f, 1e-23f, 0.0f} : Vec3f{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
    for (const bool unknown_is_free : {false, true}) {
      std::vector<Key> keys;
      ASSERT_TRUE(walker.ray_keys(from, to, keys));
      keys.push_back(map.grid().key(Vec3d(to)));
      std::optional<Key> first;
      for (const Key& k : keys) {
        const float v = dense.at(k);
        if (t.is_occupied(v) || (!unknown_is_free && t.is_unknown(v))) {
          first = k;
          break;
        }
      }
      const CollisionResult got = map.is_free(Segment{Vec3d(from), Vec3d(to)}, {unknown_is_free, 0});
      ASSERT_EQ(got.free, !first) << "segment " << i;
      if (first) {
        ASSERT_TRUE(contains(*got.blocking, *first)) << "segment " << i;
        ++blocked;
      }
    }
  }
  EXPECT_GT(blocked, 1000u);
}

TEST(Collision, BatchAnswersEqualSingleAnswers) {
  test::RandomMapSpec spec;
  spec.seed = 9;
  const OccupancyMap map = test::random_map(spec);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::vector<Sphere> spheres;
  std::vector<Segment> segments;
  for (int i = 0; i < 600; ++i) {
    spheres.push_back({{u(rng), u(rng), u(rng)}, 0.05 + 0.3 * std::fabs(u(rng)) / 1.2});
    segments.push_back({{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}});
  }
  std::vector<std::uint8_t> sphere_free(spheres.size());
  std::vector<std::uint8_t> segment_free(segments.size());
  map.is_free(std::span<const Sphere>(spheres), std::span<std::uint8_t>(sphere_free));
  map.is_free(std::span<const Segment>(segments), std::span<std::uint8_t>(segment_free));
  std::size_t free_count = 0;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    EXPECT_EQ(sphere_free[i] == 1, map.is_free(spheres[i]).free);
    EXPECT_EQ(segment_free[i] == 1, map.is_free(segments[i]).free);
    free_count += sphere_free[i];
  }
  EXPECT_GT(free_count, 0u);
  EXPECT_LT(free_count, spheres.size());
}

}  // namespace
}  // namespace umbra
