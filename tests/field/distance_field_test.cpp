// DistanceField against a brute force written from docs/design.md
// ("Distance field"): for a query point, the voxel holding it; at depth d,
// its depth-d cell; the distance from the nearest voxel centre of that cell
// to the nearest cube of a depth-d node holding an occupied (resp. unknown)
// voxel, states read through the map's public node(), geometry in metres.
// Random maps at several depths, with and without a box, auto-pruning on
// and off, thresholds changed, and after every scan of a short sequence.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <random>
#include <tuple>
#include <vector>

#include "field/brick_table.hpp"
#include "field/cell_codes.hpp"
#include "field/field_layout.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/field/distance_field.hpp"

namespace umbra {
namespace {

constexpr double kResolution = 0.1;

struct Expected {
  double occupied;
  double unknown;
  std::vector<Vec3d> gradients;  // away from each nearest blocking site (ties)
  /// Away from the one nearest blocking site the field keeps (docs/design.md,
  /// "Distance field": of equally near sites the one first in the order of
  /// offsets in cells by z, then y, then x, each 0, -1, +1, -2, +2, ...;
  /// the occupied one when an occupied and an unknown site are equally near).
  Vec3d canonical;
};

/// The rank of an offset along one axis in the order above.
int tie_rank(int d) { return d == 0 ? 0 : 2 * std::abs(d) - (d < 0 ? 1 : 0); }

class BruteForce {
 public:
  BruteForce(const OccupancyMap& map, const DistanceFieldOptions& options) : map_(map), options_(options) {
    if (options.box) {
      box_min_ = map.key(options.box->min).at_depth(options.depth);
      box_max_ = map.key(options.box->max).at_depth(options.depth);
    }
  }

  Expected at(Vec3d point) {
    const int k = options_.depth;
    const double cell = map_.grid().node_size(k);
    const double half = map_.resolution() / 2;
    const Key voxel = map_.key(point);
    const Key c = voxel.at_depth(k);
    // The cell's voxel centres span this box.
    const Vec3d cell_min = map_.grid().min_corner(Key{c.x << k, c.y << k, c.z << k}, 0);
    Vec3d lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = cell_min[a] + half;
      hi[a] = cell_min[a] + cell - half;
    }
    const int reach = int(std::ceil(options_.max_distance / cell)) + 2;
    Expected out{options_.max_distance, options_.max_distance, {}, {}};
    double best_blocking = std::numeric_limits<double>::infinity();
    // Per kind (occupied, unknown): the kept site's distance, rank and direction.
    struct Kept {
      double d = std::numeric_limits<double>::infinity();
      std::tuple<int, int, int> rank;
      Vec3d away;
    } kept[2];
    for (int dz = -reach; dz <= reach; ++dz) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const Key s{std::uint32_t(int(c.x) + dx), std::uint32_t(int(c.y) + dy), std::uint32_t(int(c.z) + dz)};
          if (options_.box && !(s.x >= box_min_.x && s.x <= box_max_.x && s.y >= box_min_.y && s.y <= box_max_.y &&
                                s.z >= box_min_.z && s.z <= box_max_.z)) {
            continue;
          }
          const auto [occupied, unknown] = state(s);
          if (!occupied && !unknown) continue;
          const Vec3d s_min = map_.grid().min_corner(Key{s.x << k, s.y << k, s.z << k}, 0);
          Vec3d away;
          double sum = 0;
          for (int a = 0; a < 3; ++a) {
            const double below = s_min[a] - hi[a];        // site above the cell
            const double above = lo[a] - (s_min[a] + cell);  // site below the cell
            const double gap = std::max({below, above, 0.0});
            away[a] = below > 0 ? -gap : (above > 0 ? gap : 0.0);
            sum += gap * gap;
          }
          const double d = std::sqrt(sum);
          const std::tuple<int, int, int> rank{tie_rank(dz), tie_rank(dy), tie_rank(dx)};
          for (int kind = 0; kind < 2; ++kind) {
            if (!(kind == 0 ? occupied : unknown)) continue;
            Kept& held = kept[kind];
            if (d < held.d - 1e-9 || (d <= held.d + 1e-9 && rank < held.rank)) held = {d, rank, d > 0 ? away * (1.0 / d) : Vec3d{}};
          }
          if (occupied) out.occupied = std::min(out.occupied, d);
          if (unknown) out.unknown = std::min(out.unknown, d);
          if (d < best_blocking - 1e-9) {
            best_blocking = d;
            out.gradients.clear();
          }
          if (d <= best_blocking + 1e-9 && d > 0) out.gradients.push_back(away * (1.0 / d));
        }
      }
    }
    if (best_blocking >= options_.max_distance || best_blocking == 0) {
      out.gradients.clear();
    } else {
      out.canonical = kept[0].d <= kept[1].d + 1e-9 ? kept[0].away : kept[1].away;
    }
    return out;
  }

 private:
  std::pair<bool, bool> state(Key cell) {
    const auto key = std::make_tuple(cell.x, cell.y, cell.z);
    if (const auto it = cache_.find(key); it != cache_.end()) return it->second;
    const int k = options_.depth;
    const Node n = map_.node(Key{cell.x << k, cell.y << k, cell.z << k}, k);
    const std::pair<bool, bool> s{n.contains_occupied(), n.contains_unknown};
    cache_.emplace(key, s);
    return s;
  }

  const OccupancyMap& map_;
  DistanceFieldOptions options_;
  Key box_min_, box_max_;
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, std::pair<bool, bool>> cache_;
};

/// A map whose voxels in [-1.2, 1.2)^3 are set at random: mostly free, some
/// occupied, some left unknown, with a few free blocks that prune.
OccupancyMap random_map(std::uint32_t seed, bool auto_prune) {
  OccupancyMap map(kResolution);
  map.set_auto_prune(auto_prune);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (double z = -1.15; z < 1.2; z += kResolution) {
    for (double y = -1.15; y < 1.2; y += kResolution) {
      for (double x = -1.15; x < 1.2; x += kResolution) {
        const bool free_block = x > 0.4 && y > 0.4;  // an all-free corner
        const double r = u(rng);
        if (free_block || r < 0.7) {
          map.set_log_odds(Vec3d{x, y, z}, -1.0f);
        } else if (r < 0.78) {
          map.set_log_odds(Vec3d{x, y, z}, 1.5f);
        }
      }
    }
  }
  return map;
}

Vec3d random_point(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> u(-extent, extent);
  return {u(rng), u(rng), u(rng)};
}

void expect_field_matches(const OccupancyMap& map, const DistanceField& field, std::uint32_t seed, int samples,
                          const char* what) {
  BruteForce brute(map, field.options());
  std::mt19937 rng(seed);
  const std::optional<Aabb>& box = field.options().box;
  for (int i = 0; i < samples; ++i) {
    Vec3d p = random_point(rng, 1.8);
    if (box) {
      for (int a = 0; a < 3; ++a) p[a] = std::clamp(p[a], box->min[a], box->max[a]);
    }
    const Expected expected = brute.at(p);
    const DistanceSample got = field.distance_and_gradient(p);
    ASSERT_NEAR(got.occupied, expected.occupied, 1e-9) << what << " at " << p.x << " " << p.y << " " << p.z;
    ASSERT_NEAR(got.unknown, expected.unknown, 1e-9) << what << " at " << p.x << " " << p.y << " " << p.z;
    // The single distance() has its own path (no gradient).
    ASSERT_NEAR(field.distance(p), std::min(expected.occupied, expected.unknown), 1e-9)
        << what << " at " << p.x << " " << p.y << " " << p.z;
    if (expected.gradients.empty()) {
      ASSERT_EQ(got.gradient.x, 0.0) << what;
      ASSERT_EQ(got.gradient.y, 0.0) << what;
      ASSERT_EQ(got.gradient.z, 0.0) << what;
    } else {
      const bool one_of_them = std::any_of(expected.gradients.begin(), expected.gradients.end(), [&](Vec3d g) {
        return std::abs(g.x - got.gradient.x) < 1e-9 && std::abs(g.y - got.gradient.y) < 1e-9 &&
               std::abs(g.z - got.gradient.z) < 1e-9;
      });
      ASSERT_TRUE(one_of_them) << what << " gradient " << got.gradient.x << " " << got.gradient.y << " "
                               << got.gradient.z << " at " << p.x << " " << p.y << " " << p.z;
    }
  }
}

TEST(DistanceField, MatchesBruteForceAtSeveralDepths) {
  for (const bool prune : {true, false}) {
    const OccupancyMap map = random_map(7, prune);
    for (int depth = 0; depth <= 2; ++depth) {
      DistanceFieldOptions options;
      options.depth = depth;
      options.max_distance = depth == 0 ? 0.43 : 0.9;
      const DistanceField field(map, options);
      expect_field_matches(map, field, 100 + depth, 400, prune ? "pruned" : "unpruned");
    }
  }
}

TEST(DistanceField, MatchesBruteForceWithAWideWindow) {
  // 1.7 m at 10 cm: a window of 17 cells, chunks of 5 bricks.
  const OccupancyMap map = random_map(13, true);
  DistanceFieldOptions options;
  options.max_distance = 1.7;
  const DistanceField field(map, options);
  expect_field_matches(map, field, 150, 60, "wide window");
}

TEST(DistanceField, MatchesBruteForceWithAWindowTooWideForCodes) {
  // 2.6 m at 10 cm: a window of 26 cells, more offsets within the cap than
  // 16-bit codes hold, so the bricks keep three int8 per kind
  // (cell_codes.hpp); the answers must not depend on the layout. Updated
  // once too (decoding and coding again).
  OccupancyMap map = random_map(14, true);
  DistanceFieldOptions options;
  options.max_distance = 2.6;
  options.depth = 0;
  DistanceField field(map, options);
  ASSERT_FALSE(detail::CellCodes(detail::FieldLayout(map.resolution(), map.depth_levels(), 0, 2.6)).compact());
  expect_field_matches(map, field, 160, 12, "window too wide for codes");
  map.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
  map.set_log_odds(Vec3d{-0.45, 0.35, 0.05}, -1.0f);
  field.update();
  expect_field_matches(map, field, 161, 12, "window too wide for codes, updated");
}

TEST(DistanceField, CellCodesRoundTripEveryOffsetWithinTheCap) {
  // Every offset a field can keep has a code and decodes to itself; a
  // brick of them (and of cells with no site) comes back unchanged.
  for (const double max_distance : {0.25, 0.9, 2.2}) {
    const detail::FieldLayout layout(kResolution, 16, 0, max_distance);
    const detail::CellCodes codes(layout);
    ASSERT_TRUE(codes.compact()) << max_distance;
    EXPECT_EQ(codes.bytes_per_cell(), 4u);
    std::vector<detail::SiteOffset> within;
    const int w = layout.window();
    for (int z = -w; z <= w; ++z) {
      for (int y = -w; y <= w; ++y) {
        for (int x = -w; x <= w; ++x) {
          const detail::SiteOffset o{std::int8_t(x), std::int8_t(y), std::int8_t(z)};
          if (layout.within_cap(layout.squared(o))) within.push_back(o);
        }
      }
    }
    within.push_back(detail::SiteOffset{});  // none
    std::vector<unsigned char> cells(codes.bytes_per_brick());
    for (std::size_t first = 0; first < within.size(); first += detail::kBrickVolume) {
      detail::BrickOffsets in{}, out{};
      for (int i = 0; i < detail::kBrickVolume; ++i) {
        in[std::size_t(i)].occupied = within[(first + std::size_t(i)) % within.size()];
        in[std::size_t(i)].unknown = within[(first + 7 * std::size_t(i) + 3) % within.size()];
      }
      codes.encode(in, cells.data());
      codes.decode(cells.data(), out);
      for (int i = 0; i < detail::kBrickVolume; ++i) {
        for (const auto& [a, b] : {std::pair{in[std::size_t(i)].occupied, out[std::size_t(i)].occupied},
                                   std::pair{in[std::size_t(i)].unknown, out[std::size_t(i)].unknown}}) {
          ASSERT_EQ(a.x, b.x) << max_distance << " cell " << i;
          ASSERT_EQ(a.y, b.y) << max_distance << " cell " << i;
          ASSERT_EQ(a.z, b.z) << max_distance << " cell " << i;
        }
        const detail::CellSites one = codes.cell(cells.data(), i);
        ASSERT_EQ(one.occupied.x, in[std::size_t(i)].occupied.x);
        ASSERT_EQ(one.unknown.z, in[std::size_t(i)].unknown.z);
      }
    }
  }
}

TEST(DistanceField, StoresFourBytesACellWithASmallWindow) {
  // docs/benchmarks.md ("Distance field", memory): within a window whose
  // offsets fit 16-bit codes a stored brick costs its sites, its bounds and
  // 4 bytes a cell, under 4.5 bytes a cell with the table's slots.
  // Against an empty map's field (no bricks) with the same options, so
  // that the fixed part (the code tables, about 0.3 MB) drops out; 6.3
  // bytes a cell before the codes.
  const OccupancyMap map = random_map(15, true);
  const OccupancyMap empty(kResolution);
  DistanceFieldOptions options;
  options.max_distance = 0.9;
  const DistanceField field(map, options);
  const DistanceField none(empty, options);
  ASSERT_EQ(none.stats().bricks, 0u);
  const DistanceFieldStats stats = field.stats();
  ASSERT_GT(stats.bricks, 100u);
  const double per_cell = double(stats.memory_bytes - none.stats().memory_bytes) / double(stats.bricks * detail::kBrickVolume);
  EXPECT_LT(per_cell, 4.5);
}

TEST(DistanceField, MatchesBruteForceInsideABox) {
  const OccupancyMap map = random_map(8, true);
  DistanceFieldOptions options;
  options.max_distance = 0.55;
  // Reaching far beyond the known space: bricks there are all unknown.
  options.box = Aabb{{-0.9, -0.5, -0.75}, {2.9, 1.1, 0.3}};
  const DistanceField field(map, options);
  expect_field_matches(map, field, 200, 400, "box");
  EXPECT_THROW((void)field.distance({3.5, 0.0, 0.0}), std::out_of_range);
}

TEST(DistanceField, SphereIsFreeIffRadiusBelowDistance) {
  const OccupancyMap map = random_map(9, true);
  for (int depth = 0; depth <= 1; ++depth) {
    DistanceFieldOptions options;
    options.depth = depth;
    options.max_distance = 0.8;
    const DistanceField field(map, options);
    std::mt19937 rng(300);
    int checked = 0;
    for (int i = 0; i < 300; ++i) {
      const Vec3d centre = map.grid().center(map.key(random_point(rng, 1.5)));
      const double d = field.distance(centre);
      CollisionOptions collision;
      collision.depth = depth;
      if (d > 0) {
        EXPECT_TRUE(map.is_free(Sphere{centre, d * (1 - 1e-9)}, collision)) << "depth " << depth;
      }
      if (depth == 0 && d < options.max_distance) {
        EXPECT_FALSE(map.is_free(Sphere{centre, d * (1 + 1e-9) + 1e-12}, collision));
        ++checked;
      }
    }
    if (depth == 0) {
      EXPECT_GT(checked, 100);
    }
  }
}

TEST(DistanceField, CoarseIsNeverLargerThanFine) {
  const OccupancyMap map = random_map(10, true);
  DistanceFieldOptions fine_options;
  fine_options.max_distance = 1.0;
  const DistanceField fine(map, fine_options);
  std::mt19937 rng(400);
  for (int depth = 1; depth <= 3; ++depth) {
    DistanceFieldOptions options = fine_options;
    options.depth = depth;
    const DistanceField coarse(map, options);
    for (int i = 0; i < 500; ++i) {
      const Vec3d p = random_point(rng, 2.0);
      const DistanceSample c = coarse.distance_and_gradient(p);
      const DistanceSample f = fine.distance_and_gradient(p);
      ASSERT_LE(c.occupied, f.occupied + 1e-12) << "depth " << depth;
      ASSERT_LE(c.unknown, f.unknown + 1e-12) << "depth " << depth;
    }
  }
}

TEST(DistanceField, BatchAnswersAsSingleQueries) {
  const OccupancyMap map = random_map(11, true);
  const DistanceField field(map, {});
  std::mt19937 rng(500);
  std::vector<Vec3d> points(1000);
  for (Vec3d& p : points) p = random_point(rng, 2.0);
  std::vector<double> distances(points.size());
  std::vector<DistanceSample> samples(points.size());
  field.distance(points, distances);
  field.distance_and_gradient(points, samples);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const DistanceSample one = field.distance_and_gradient(points[i]);
    ASSERT_EQ(distances[i], one.blocking());
    ASSERT_EQ(samples[i].occupied, one.occupied);
    ASSERT_EQ(samples[i].unknown, one.unknown);
  }
  points[3] = {1e9, 0, 0};
  try {
    field.distance(points, distances);
    FAIL() << "a point outside the map must throw";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(field.distance(points, std::span<double>(distances).first(5)), std::invalid_argument);
}

TEST(DistanceField, RejectsBadOptions) {
  const OccupancyMap map(kResolution);
  DistanceFieldOptions options;
  options.max_distance = 0.0;
  EXPECT_THROW(DistanceField(map, options), std::invalid_argument);
  options.max_distance = std::nan("");
  EXPECT_THROW(DistanceField(map, options), std::invalid_argument);
  options.max_distance = 1.0;
  options.depth = 14;
  EXPECT_THROW(DistanceField(map, options), std::invalid_argument);
  options.depth = 0;
  options.max_distance = 100.0;  // 1000 cells
  EXPECT_THROW(DistanceField(map, options), std::invalid_argument);
  options.max_distance = 1.0;
  options.box = Aabb{{0, 0, 0}, {1e6, 1, 1}};
  EXPECT_THROW(DistanceField(map, options), std::out_of_range);
}

/// Points on the walls of a 2 m room around the origin, seen from `origin`.
std::vector<Vec3f> room_scan(std::mt19937& rng, int count) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> wall(0, 5);
  std::vector<Vec3f> points;
  for (int i = 0; i < count; ++i) {
    Vec3f p{u(rng), u(rng), u(rng)};
    const int w = wall(rng);
    p[w / 2] = w % 2 == 0 ? -1.05f : 1.05f;
    points.push_back(p);
  }
  return points;
}

TEST(DistanceField, UpdatedAfterEveryScanAsBruteForce) {
  for (const bool prune : {true, false}) {
    for (const bool boxed : {false, true}) {
      OccupancyMap map(kResolution);
      map.set_auto_prune(prune);
      DistanceFieldOptions options;
      options.max_distance = 0.45;
      options.threads = boxed ? 3 : 1;  // chunks in parallel give the same field
      if (boxed) options.box = Aabb{{-1.3, -1.0, -0.8}, {2.5, 1.3, 1.2}};
      DistanceField field(map, options);
      std::mt19937 rng(600);
      std::uniform_real_distribution<float> origin(-0.5f, 0.5f);
      for (int scan = 0; scan < 6; ++scan) {
        map.insert_point_cloud({origin(rng), origin(rng), origin(rng)}, room_scan(rng, 300));
        field.update();
        expect_field_matches(map, field, 700 + scan, 150, boxed ? "after a scan, boxed" : "after a scan");
      }
      // Single voxels, then thresholds changed at run time.
      map.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
      field.update();
      expect_field_matches(map, field, 800, 150, "after a voxel");
      map.set_thresholds({0.8, 0.3});
      field.update();
      expect_field_matches(map, field, 801, 150, "after new thresholds");
      map.clear();
      field.update();
      expect_field_matches(map, field, 802, 50, "after clear");
    }
  }
}

TEST(DistanceField, UpdatedAsBruteForceWhenObstaclesComeAndGo) {
  // Few obstacles in free space, so that removing one raises distances far
  // around it (the cells whose nearest site went are transformed again),
  // adding one lowers them (the others are lowered by the added sites
  // only), and unknown space seen as free raises the unknown distances.
  for (const bool boxed : {false, true}) {
    OccupancyMap map(kResolution);
    for (double z = -0.55; z < 0.6; z += kResolution) {
      for (double y = -1.15; y < 1.2; y += kResolution) {
        for (double x = -1.15; x < 1.2; x += kResolution) map.set_log_odds(Vec3d{x, y, z}, -1.0f);
      }
    }
    DistanceFieldOptions options;
    options.max_distance = 0.65;
    options.threads = boxed ? 2 : 1;
    if (boxed) options.box = Aabb{{-1.0, -1.3, -0.9}, {1.6, 0.9, 1.4}};
    DistanceField field(map, options);
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1.15, 1.15);
    std::vector<Vec3d> obstacles;
    for (int step = 0; step < 8; ++step) {
      // Half of the obstacles go (free again), new ones come, one more
      // layer of unknown space becomes free.
      std::shuffle(obstacles.begin(), obstacles.end(), rng);
      for (std::size_t i = obstacles.size() / 2; i < obstacles.size(); ++i) map.set_log_odds(obstacles[i], -1.0f);
      obstacles.resize(obstacles.size() / 2);
      for (int i = 0; i < 6; ++i) {
        obstacles.push_back({u(rng), u(rng), 0.5 * u(rng)});
        map.set_log_odds(obstacles.back(), 2.0f);
      }
      const double layer = 0.65 + 0.1 * step;
      for (double y = -1.15; y < 0.2; y += kResolution) {
        for (double x = -0.55; x < 1.2; x += kResolution) map.set_log_odds(Vec3d{x, y, layer}, -1.0f);
      }
      field.update();
      expect_field_matches(map, field, 900 + std::uint32_t(step), 250,
                           boxed ? "obstacles come and go, boxed" : "obstacles come and go");
    }
  }
}

TEST(DistanceField, UpdatedAnswersAsARebuiltOne) {
  // Bit for bit, gradients included: where two sites are equally near, an
  // update must keep the one a rebuild keeps (readers and the Python
  // tests compare an updated field with a fresh one).
  for (const bool boxed : {true, false}) {
    OccupancyMap map(kResolution);
    DistanceFieldOptions options;
    options.max_distance = 0.4;
    if (boxed) options.box = Aabb{{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}};
    DistanceField field(map, options);
    std::mt19937 rng(boxed ? 4 : 5);
    std::uniform_real_distribution<double> u(-1.0, 1.0), probe_coordinate(-1.4, 1.4), origin(-0.3, 0.3);
    std::vector<Vec3d> probe(3000);
    for (Vec3d& p : probe) p = {probe_coordinate(rng), probe_coordinate(rng), probe_coordinate(rng)};
    for (int scan = 0; scan < 4; ++scan) {
      std::vector<Vec3f> points(500);
      for (Vec3f& p : points) {
        double c[3] = {u(rng), u(rng), u(rng)};
        c[scan % 3] = 1.05;  // a wall
        p = Vec3f(float(c[0]), float(c[1]), float(c[2]));
      }
      map.insert_point_cloud(Vec3f(float(origin(rng)), float(origin(rng)), float(origin(rng))), points);
      field.update();
      const DistanceField fresh(map, options);
      for (const Vec3d& p : probe) {
        const DistanceSample a = field.distance_and_gradient(p);
        const DistanceSample b = fresh.distance_and_gradient(p);
        ASSERT_EQ(a.occupied, b.occupied) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_EQ(a.unknown, b.unknown) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_EQ(a.gradient.x, b.gradient.x) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_EQ(a.gradient.y, b.gradient.y) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_EQ(a.gradient.z, b.gradient.z) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
      }
    }
  }
}

TEST(DistanceField, KeepsTheCanonicalOneOfEquallyNearSites) {
  // The transform and the update's lowering keep, of equally near sites,
  // the one first in a fixed order of offsets (tie_rank): that is what
  // makes an updated field equal a rebuilt one without transforming again
  // where an added site ties. Checked on fresh fields at two depths and
  // after each scan of a sequence (lowered bricks), with and without a box.
  for (const int depth : {0, 1}) {
    const OccupancyMap random = random_map(40 + std::uint32_t(depth), true);
    DistanceFieldOptions options;
    options.max_distance = 0.5;
    options.depth = depth;
    const DistanceField fresh(random, options);
    BruteForce brute(random, options);
    std::mt19937 rng(41);
    for (int i = 0; i < 300; ++i) {
      const Vec3d p = random_point(rng, 1.6);
      const Expected e = brute.at(p);
      const DistanceSample got = fresh.distance_and_gradient(p);
      ASSERT_NEAR(got.gradient.x, e.canonical.x, 1e-9) << "depth " << depth << " at " << p.x << " " << p.y << " " << p.z;
      ASSERT_NEAR(got.gradient.y, e.canonical.y, 1e-9) << "depth " << depth << " at " << p.x << " " << p.y << " " << p.z;
      ASSERT_NEAR(got.gradient.z, e.canonical.z, 1e-9) << "depth " << depth << " at " << p.x << " " << p.y << " " << p.z;
    }
  }
  for (const bool boxed : {false, true}) {
    OccupancyMap map(kResolution);
    DistanceFieldOptions options;
    options.max_distance = 0.45;
    if (boxed) options.box = Aabb{{-1.3, -1.2, -1.1}, {1.4, 1.3, 1.2}};
    DistanceField field(map, options);
    std::mt19937 rng(boxed ? 42 : 43);
    std::uniform_real_distribution<float> origin(-0.4f, 0.4f);
    for (int scan = 0; scan < 4; ++scan) {
      map.insert_point_cloud({origin(rng), origin(rng), origin(rng)}, room_scan(rng, 400));
      field.update();
      BruteForce brute(map, options);
      for (int i = 0; i < 200; ++i) {
        const Vec3d p = random_point(rng, 1.05);
        const Expected e = brute.at(p);
        const DistanceSample got = field.distance_and_gradient(p);
        ASSERT_NEAR(got.gradient.x, e.canonical.x, 1e-9) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_NEAR(got.gradient.y, e.canonical.y, 1e-9) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
        ASSERT_NEAR(got.gradient.z, e.canonical.z, 1e-9) << "scan " << scan << " at " << p.x << " " << p.y << " " << p.z;
      }
    }
  }
}

TEST(DistanceField, UpdateRecomputesOnlyNearChanges) {
  OccupancyMap map = random_map(12, true);
  DistanceFieldOptions options;
  options.max_distance = 0.3;
  DistanceField field(map, options);
  const std::size_t all = field.stats().bricks;
  map.set_log_odds(Vec3d{0.05, 0.05, 0.05}, 2.0f);
  field.update();
  EXPECT_EQ(field.stats().bricks_reread, 1u);
  EXPECT_LT(field.stats().bricks_recomputed, all);
  EXPECT_GT(field.stats().bricks_recomputed, 0u);
  field.update();  // nothing new
  EXPECT_EQ(field.stats().bricks_recomputed, 0u);
}

TEST(DistanceField, BrickMarksActAsASet) {
  // An update's candidate set: a bitmap over the box of its bricks when
  // that is small, a hash set when not; both must act as a set.
  for (const std::uint32_t extent : {20u, 1u << 20}) {
    const std::uint32_t lo[3] = {5, 7, 9};
    const std::uint32_t hi[3] = {5 + extent, 7 + 29, 9 + 19};
    detail::BrickMarks marks(lo, hi);
    std::set<std::uint64_t> reference;
    std::mt19937 rng(extent);
    for (int step = 0; step < 20000; ++step) {
      const detail::BrickIndex b{lo[0] + std::uint32_t(rng() % (std::min(extent, 40u) + 1)), lo[1] + std::uint32_t(rng() % 30),
                                 lo[2] + std::uint32_t(rng() % 20)};
      const std::uint64_t key = b.packed();
      ASSERT_EQ(marks.contains(b.x, b.y, b.z, key), reference.contains(key)) << "extent " << extent << " step " << step;
      ASSERT_EQ(marks.insert(b.x, b.y, b.z, key), reference.insert(key).second) << "extent " << extent << " step " << step;
    }
  }
}

TEST(DistanceField, BrickTableActsAsAMap) {
  detail::BrickTable<int> table;
  std::map<std::uint64_t, int> reference;
  std::mt19937_64 rng(900);
  for (int step = 0; step < 20000; ++step) {
    const std::uint64_t key = rng() % 3000;  // collisions and reuse
    if (rng() % 3 == 0) {
      table.erase(key);
      reference.erase(key);
    } else {
      table.insert_or_assign(key, std::make_unique<int>(step));
      reference[key] = step;
    }
  }
  ASSERT_EQ(table.size(), reference.size());
  for (std::uint64_t key = 0; key < 3000; ++key) {
    const int* found = table.find(key);
    const auto it = reference.find(key);
    ASSERT_EQ(found != nullptr, it != reference.end()) << key;
    if (found != nullptr) {
      ASSERT_EQ(*found, it->second);
    }
  }
}

}  // namespace
}  // namespace umbra
