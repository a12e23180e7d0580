// Predicates and iteration against brute force: random maps (pruned blocks,
// scattered voxels, scans), every predicate alone and in random && || !
// combinations, at several query depths, with automatic pruning on and off
// and thresholds changed at run time. The expected nodes come from a naive
// enumeration of the tree through point lookups (support/query_oracle) and
// the predicates' definitions evaluated over the dense voxel values, so the
// pruned walk must yield exactly the same nodes, in the same order, each
// exactly once, with the right values and indicators.
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "support/query_oracle.hpp"
#include "support/shape_oracle.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra {
namespace {

using test::OracleNode;

// --- the shapes' meaning: support/shape_oracle ---------------------------------------

using test::clamp_distance_squared;
using test::Cube;
using test::meets;

Cube cube_of(const Grid& grid, const OracleNode& n) {
  const Vec3d low = grid.min_corner(n.key, n.depth);
  const double size = grid.node_size(n.depth);
  return {low, low + Vec3d{size, size, size}};
}

// --- random predicates with their brute-force meaning ------------------------------

/// What an atom needs to judge a node.
struct Facts {
  const OracleNode& node;
  const test::DenseValues::Summary& summary;
  const Cube& cube;
};

struct Expr {
  std::string text;
  Predicate predicate;
  std::function<bool(const Facts&)> holds;
};

Expr operator&&(const Expr& a, const Expr& b) {
  return {"(" + a.text + " && " + b.text + ")", a.predicate && b.predicate,
          [a, b](const Facts& f) { return a.holds(f) && b.holds(f); }};
}
Expr operator||(const Expr& a, const Expr& b) {
  return {"(" + a.text + " || " + b.text + ")", a.predicate || b.predicate,
          [a, b](const Facts& f) { return a.holds(f) || b.holds(f); }};
}
Expr operator!(const Expr& a) {
  return {"!" + a.text, !a.predicate, [a](const Facts& f) { return !a.holds(f); }};
}

/// Per finest voxel: is it one of the set (a segment's walk, a frustum's centres)?
using VoxelSet = std::vector<bool>;

bool any_voxel_in(const VoxelSet& set, std::uint32_t size, const OracleNode& n) {
  const std::uint32_t edge = 1u << n.depth;
  for (std::uint32_t z = 0; z < edge; ++z) {
    for (std::uint32_t y = 0; y < edge; ++y) {
      for (std::uint32_t x = 0; x < edge; ++x) {
        const std::size_t i = (std::size_t{n.key.z + z} * size + (n.key.y + y)) * size + (n.key.x + x);
        if (set[i]) return true;
      }
    }
  }
  return false;
}

class Atoms {
 public:
  Atoms(const OccupancyMap& map, std::mt19937& rng) : map_(map), rng_(rng) {}

  Expr random() {
    const int which = std::uniform_int_distribution<int>(0, 16)(rng_);
    const LogOddsThresholds t = LogOddsThresholds::from(map_.thresholds());
    const int levels = map_.depth_levels();
    const int k = std::uniform_int_distribution<int>(0, levels)(rng_);
    switch (which) {
      case 0: return {"occupied", pred::occupied(), [t](const Facts& f) { return t.is_occupied(f.summary.max); }};
      case 1: return {"free", pred::free(), [t](const Facts& f) { return t.is_free(f.summary.max); }};
      case 2: return {"unknown", pred::unknown(), [t](const Facts& f) { return t.is_unknown(f.summary.max); }};
      case 3:
        return {"contains_occupied", pred::contains_occupied(),
                [t](const Facts& f) { return t.is_occupied(f.summary.max); }};
      case 4: return {"contains_free", pred::contains_free(), [](const Facts& f) { return f.summary.any_free; }};
      case 5:
        return {"contains_unknown", pred::contains_unknown(), [](const Facts& f) { return f.summary.any_unknown; }};
      case 6: return {"leaf", pred::leaf(), [](const Facts& f) { return f.node.leaf; }};
      case 7:
        return {"depth==" + std::to_string(k), pred::depth(k), [k](const Facts& f) { return f.node.depth == k; }};
      case 8:
        return {"depth>=" + std::to_string(k), pred::min_depth(k), [k](const Facts& f) { return f.node.depth >= k; }};
      case 9:
        return {"depth<=" + std::to_string(k), pred::max_depth(k), [k](const Facts& f) { return f.node.depth <= k; }};
      case 10: {
        const Vec3d a = point();
        const Vec3d b = point();
        const Aabb box{{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
                       {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}};
        return {"box", pred::intersects(box), [box](const Facts& f) { return meets(box, f.cube); }};
      }
      case 11: {
        const Sphere s{point(), length(0.02, 1.2)};
        return {"sphere", pred::intersects(s), [s](const Facts& f) { return meets(s, f.cube); }};
      }
      case 12: {
        std::normal_distribution<double> n;
        const OrientedBox box = OrientedBox::from_quaternion(
            point(), {length(0.01, 0.8), length(0.01, 0.8), length(0.01, 0.8)}, n(rng_), n(rng_), n(rng_), n(rng_));
        return {"oriented_box", pred::intersects(box), [box](const Facts& f) { return meets(box, f.cube); }};
      }
      case 13: {
        const Capsule c{point(), point(), length(0.0, 0.5)};
        return {"capsule", pred::intersects(c), [c](const Facts& f) { return meets(c, f.cube); }};
      }
      case 14: {
        const Segment s{point(), point()};
        auto set = std::make_shared<VoxelSet>(segment_voxels(s));
        const std::uint32_t size = map_.grid().keys_per_axis();
        return {"segment", pred::intersects(s), [set, size](const Facts& f) { return any_voxel_in(*set, size, f.node); }};
      }
      case 15: {
        constexpr double deg = std::numbers::pi / 180.0;
        const double min_range = length(0.0, 0.6);
        const Frustum fr{point(), length(-3.2, 3.2), length(-1.4, 1.4), length(20, 170) * deg, length(15, 150) * deg,
                         min_range, min_range + length(0.2, 3.0)};
        auto set = std::make_shared<VoxelSet>(frustum_voxels(fr));
        const std::uint32_t size = map_.grid().keys_per_axis();
        return {"frustum", pred::intersects(fr), [set, size](const Facts& f) { return any_voxel_in(*set, size, f.node); }};
      }
      default: {
        const float above = static_cast<float>(length(-1.0, 1.0));
        return {"rule(log_odds>" + std::to_string(above) + ")",
                pred::satisfies([above](const Node& n) { return n.log_odds > above; }),
                [above, this](const Facts& f) { return map_.node(f.node.key, f.node.depth).log_odds > above; }};
      }
    }
  }

  /// A random expression of up to `depth` levels of operators.
  Expr random_expression(int depth) {
    if (depth == 0) return random();
    switch (std::uniform_int_distribution<int>(0, 3)(rng_)) {
      case 0: return random_expression(depth - 1) && random_expression(depth - 1);
      case 1: return random_expression(depth - 1) || random_expression(depth - 1);
      case 2: return !random_expression(depth - 1);
      default: return random();
    }
  }

 private:
  double length(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  Vec3d point() {
    const double h = map_.grid().half_extent() * 0.98;
    return {length(-h, h), length(-h, h), length(-h, h)};
  }
  VoxelSet segment_voxels(const Segment& s) const {
    const Grid& grid = map_.grid();
    const std::uint32_t size = grid.keys_per_axis();
    test::DenseGrid walker(grid.resolution(), grid.depth_levels(), -2.0f, 3.5f);
    std::vector<Key> keys;
    EXPECT_TRUE(walker.ray_keys(Vec3f(s.from), Vec3f(s.to), keys));
    keys.push_back(grid.key(Vec3d(Vec3f(s.to))));
    VoxelSet set(std::size_t{size} * size * size, false);
    for (const Key& k : keys) set[(std::size_t{k.z} * size + k.y) * size + k.x] = true;
    return set;
  }
  VoxelSet frustum_voxels(const Frustum& f) const {
    const Grid& grid = map_.grid();
    const std::uint32_t size = grid.keys_per_axis();
    VoxelSet set(std::size_t{size} * size * size, false);
    for (std::uint32_t z = 0; z < size; ++z) {
      for (std::uint32_t y = 0; y < size; ++y) {
        for (std::uint32_t x = 0; x < size; ++x) {
          set[(std::size_t{z} * size + y) * size + x] = f.contains(grid.center(Key{x, y, z}));
        }
      }
    }
    return set;
  }

  const OccupancyMap& map_;
  std::mt19937& rng_;
};

struct Expected {
  std::vector<OracleNode> nodes;
  std::vector<test::DenseValues::Summary> summaries;
  std::vector<Cube> cubes;
};

Expected expected_nodes(const OccupancyMap& map, const test::DenseValues& dense, int query_depth) {
  Expected e;
  e.nodes = test::enumerate_nodes(map, query_depth);
  const LogOddsThresholds t = LogOddsThresholds::from(map.thresholds());
  for (const OracleNode& n : e.nodes) {
    e.summaries.push_back(dense.summarize(n.key, n.depth, t));
    e.cubes.push_back(cube_of(map.grid(), n));
  }
  return e;
}

void check_query(const OccupancyMap& map, const Expected& all, const Expr& expr, int query_depth,
                 const std::string& where) {
  SCOPED_TRACE(where + " predicate " + expr.text + " at depth " + std::to_string(query_depth));
  std::vector<std::size_t> wanted;
  for (std::size_t i = 0; i < all.nodes.size(); ++i) {
    if (expr.holds({all.nodes[i], all.summaries[i], all.cubes[i]})) wanted.push_back(i);
  }
  const LogOddsThresholds t = LogOddsThresholds::from(map.thresholds());
  std::size_t found = 0;
  for (const Node& node : map.query(expr.predicate, query_depth)) {
    ASSERT_LT(found, wanted.size()) << "more nodes than expected; extra: depth " << node.depth;
    const OracleNode& want = all.nodes[wanted[found]];
    const test::DenseValues::Summary& s = all.summaries[wanted[found]];
    ASSERT_EQ(node.key, want.key) << "node " << found << " (depth " << node.depth << " vs " << want.depth << ")";
    ASSERT_EQ(node.depth, want.depth);
    EXPECT_EQ(node.log_odds, s.max);
    EXPECT_EQ(node.state, t.classify(s.max));
    EXPECT_EQ(node.contains_free, s.any_free);
    EXPECT_EQ(node.contains_unknown, s.any_unknown);
    EXPECT_EQ(node.size, map.grid().node_size(want.depth));
    EXPECT_EQ(node.center, map.grid().center(want.key, want.depth));
    ++found;
  }
  EXPECT_EQ(found, wanted.size()) << "fewer nodes than expected";
  EXPECT_EQ(map.count(expr.predicate, query_depth), wanted.size());
}

void check_nearest(const OccupancyMap& map, const Expected& all, const Expr& expr, int query_depth, Vec3d point,
                   double max_distance, const std::string& where) {
  SCOPED_TRACE(where + " nearest " + expr.text);
  std::vector<std::pair<double, std::size_t>> wanted;
  for (std::size_t i = 0; i < all.nodes.size(); ++i) {
    if (!expr.holds({all.nodes[i], all.summaries[i], all.cubes[i]})) continue;
    const double d = std::sqrt(clamp_distance_squared(point, all.cubes[i]));
    if (d <= max_distance) wanted.push_back({d, i});
  }
  std::vector<std::pair<Key, int>> got;
  double last = 0.0;
  for (const NearNode& near : map.query_nearest(point, expr.predicate, query_depth, max_distance)) {
    EXPECT_GE(near.distance, last) << "not nearest first";
    last = near.distance;
    const Cube c = {near.node.min_corner(), near.node.max_corner()};
    EXPECT_NEAR(near.distance, std::sqrt(clamp_distance_squared(point, c)), 1e-9);
    got.push_back({near.node.key, near.node.depth});
  }
  ASSERT_EQ(got.size(), wanted.size());
  std::sort(wanted.begin(), wanted.end());
  // Same set (ties in distance may come in any order).
  auto key_less = [](const std::pair<Key, int>& a, const std::pair<Key, int>& b) {
    return std::tie(a.first.x, a.first.y, a.first.z, a.second) < std::tie(b.first.x, b.first.y, b.first.z, b.second);
  };
  std::vector<std::pair<Key, int>> want_set;
  for (const auto& [d, i] : wanted) want_set.push_back({all.nodes[i].key, all.nodes[i].depth});
  std::sort(got.begin(), got.end(), key_less);
  std::sort(want_set.begin(), want_set.end(), key_less);
  EXPECT_TRUE(got == want_set);
}

struct Config {
  int depth_levels;
  bool auto_prune;
  unsigned seed;
};

class PredicateQuery : public testing::TestWithParam<Config> {};

TEST_P(PredicateQuery, YieldsExactlyTheNodesBruteForceFinds) {
  const Config c = GetParam();
  test::RandomMapSpec spec;
  spec.depth_levels = c.depth_levels;
  spec.auto_prune = c.auto_prune;
  spec.seed = c.seed;
  OccupancyMap map = test::random_map(spec);
  std::mt19937 rng(c.seed * 7919u);
  // Default thresholds, then a band of unknown values, set at run time.
  for (const Thresholds thresholds : {Thresholds{0.5, 0.5}, Thresholds{0.6, 0.45}}) {
    map.set_thresholds(thresholds);
    const test::DenseValues dense(map);
    for (const int query_depth : {0, 1, 3}) {
      const Expected all = expected_nodes(map, dense, query_depth);
      Atoms atoms(map, rng);
      const std::string where = "levels " + std::to_string(c.depth_levels) + (c.auto_prune ? " pruned" : " unpruned") +
                                " thresholds " + std::to_string(thresholds.free) + "/" +
                                std::to_string(thresholds.occupied);
      // Every atom alone, then combinations.
      for (int i = 0; i < 40; ++i) check_query(map, all, atoms.random(), query_depth, where);
      for (int i = 0; i < 40; ++i) check_query(map, all, atoms.random_expression(3), query_depth, where);
      for (int i = 0; i < 6; ++i) {
        const double h = map.grid().half_extent();
        std::uniform_real_distribution<double> u(-h, h);
        check_nearest(map, all, atoms.random_expression(1), query_depth, {u(rng), u(rng), u(rng)},
                      i % 2 == 0 ? 1e9 : 0.8, where);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Maps, PredicateQuery,
                         testing::Values(Config{4, true, 1}, Config{4, false, 2}, Config{5, true, 3},
                                         Config{5, false, 4}),
                         [](const testing::TestParamInfo<Config>& param_info) {
                           return "levels" + std::to_string(param_info.param.depth_levels) +
                                  (param_info.param.auto_prune ? "_pruned" : "_unpruned");
                         });

TEST(PredicateQuery, LeavesTileTheMapExactlyOnce) {
  for (const bool prune : {true, false}) {
    test::RandomMapSpec spec;
    spec.auto_prune = prune;
    spec.seed = 11;
    const OccupancyMap map = test::random_map(spec);
    for (const int depth : {0, 2, 4}) {
      std::uint64_t voxels = 0;
      std::vector<std::uint8_t> seen(std::size_t{map.grid().keys_per_axis()} * map.grid().keys_per_axis() *
                                         map.grid().keys_per_axis(),
                                     0);
      for (const Node& node : map.query(pred::leaf(), depth)) {
        EXPECT_GE(node.depth, depth);
        const std::uint32_t edge = 1u << node.depth;
        voxels += std::uint64_t{edge} * edge * edge;
        for (std::uint32_t z = 0; z < edge; ++z) {
          for (std::uint32_t y = 0; y < edge; ++y) {
            for (std::uint32_t x = 0; x < edge; ++x) {
              const std::uint32_t n = map.grid().keys_per_axis();
              ++seen[(std::size_t{node.key.z + z} * n + node.key.y + y) * n + node.key.x + x];
            }
          }
        }
      }
      EXPECT_EQ(voxels, seen.size());
      EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](std::uint8_t s) { return s == 1; }))
          << "some voxel is covered twice or not at all (prune " << prune << ", depth " << depth << ")";
    }
  }
}

TEST(PredicateQuery, BadArgumentsAreRefusedWithAMessage) {
  const OccupancyMap map(0.1, 5);
  EXPECT_THROW((void)map.query(pred::any(), 6), std::out_of_range);
  EXPECT_THROW((void)map.query(pred::any(), -1), std::out_of_range);
  EXPECT_THROW((void)pred::intersects(Sphere{{0, 0, 0}, -1.0}), std::invalid_argument);
  EXPECT_THROW((void)pred::intersects(Sphere{{0, std::nan(""), 0}, 1.0}), std::invalid_argument);
  EXPECT_THROW((void)pred::depth(-2), std::invalid_argument);
  EXPECT_THROW((void)pred::intersects(Frustum{{0, 0, 0}, 0, 0, 4.0, 1.0, 0.0, 2.0}), std::invalid_argument);
  // A segment leaving the map cannot be walked.
  EXPECT_THROW((void)map.count(pred::intersects(Segment{{0, 0, 0}, {100, 0, 0}})), std::out_of_range);
}

}  // namespace
}  // namespace umbra
