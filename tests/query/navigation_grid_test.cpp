// The navigation grid (project_to_grid) against brute force over the dense
// voxel values of random maps: several depths, automatic pruning on and
// off, thresholds changed at run time, both rules, cells of depth 0 to 2,
// and bands whose bounds lie on voxel faces, inside voxels and past the map.
//
// Brute force, written from navigation_grid.hpp's definition and sharing no
// code with the walk: voxel row k (lower face (k - offset) * res, upper face
// one res higher) is in the band when its half-open interval [lower, upper)
// meets [z_min, z_max]; a cell's states are those of the band voxels of its
// 2^d x 2^d columns; the extent is the block of cells holding a known voxel.
// The resolution is a power of two so that faces are exact numbers.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/query_oracle.hpp"
#include "umbra/core/log_odds.hpp"
#include "umbra/core/memory_limit.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra {
namespace {

constexpr double kResolution = 0.125;

/// The grid project_to_grid must return, by brute force.
NavigationGrid brute_force(const OccupancyMap& map, const test::DenseValues& dense, const ProjectionOptions& o) {
  const std::uint32_t size = dense.size();
  const auto offset = static_cast<std::int64_t>(map.grid().key_offset());
  const double res = map.resolution();
  const LogOddsThresholds t = LogOddsThresholds::from(map.thresholds());
  std::vector<std::uint32_t> rows;
  for (std::uint32_t k = 0; k < size; ++k) {
    const double lower = double(std::int64_t(k) - offset) * res;
    if (lower <= o.z_max && lower + res > o.z_min) rows.push_back(k);
  }
  const std::uint32_t cells = size >> o.depth;
  // bit 0 occupied, bit 1 free, bit 2 unknown
  std::vector<std::uint8_t> states(std::size_t{cells} * cells, 0);
  for (std::uint32_t y = 0; y < size; ++y) {
    for (std::uint32_t x = 0; x < size; ++x) {
      std::uint8_t& s = states[std::size_t{y >> o.depth} * cells + (x >> o.depth)];
      for (const std::uint32_t z : rows) {
        const float v = dense.at({x, y, z});
        s |= t.is_occupied(v) ? 1 : t.is_free(v) ? 2 : 4;
      }
    }
  }
  NavigationGrid want;
  want.depth = o.depth;
  want.resolution = res * double(1u << o.depth);
  std::uint32_t x0 = cells, y0 = cells, x1 = 0, y1 = 0;
  for (std::uint32_t y = 0; y < cells; ++y) {
    for (std::uint32_t x = 0; x < cells; ++x) {
      if (states[std::size_t{y} * cells + x] & 3) {
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
    }
  }
  if (x0 == cells) return want;  // nothing known: the empty grid
  want.width = x1 - x0 + 1;
  want.height = y1 - y0 + 1;
  want.origin_x = double(std::int64_t(x0 << o.depth) - offset) * res;
  want.origin_y = double(std::int64_t(y0 << o.depth) - offset) * res;
  for (std::uint32_t y = y0; y <= y1; ++y) {
    for (std::uint32_t x = x0; x <= x1; ++x) {
      const std::uint8_t s = states[std::size_t{y} * cells + x];
      const bool free = o.rule == ProjectionRule::all_known ? s == 2 : (s & 2) != 0;
      want.cells.push_back((s & 1) ? GridCell::occupied : free ? GridCell::free : GridCell::unknown);
    }
  }
  return want;
}

std::string describe(const ProjectionOptions& o) {
  return "z " + std::to_string(o.z_min) + " .. " + std::to_string(o.z_max) + " depth " + std::to_string(o.depth) +
         " rule " + std::string(to_string(o.rule));
}

struct Config {
  int depth_levels;
  bool auto_prune;
  unsigned seed;
  bool sparse = false;  ///< a few scattered voxels only: the extent is a small part of the map
};

class NavigationGridBruteForce : public testing::TestWithParam<Config> {};

TEST_P(NavigationGridBruteForce, EqualsTheDenseProjection) {
  const Config c = GetParam();
  test::RandomMapSpec spec;
  spec.depth_levels = c.depth_levels;
  spec.resolution = kResolution;
  spec.auto_prune = c.auto_prune;
  spec.seed = c.seed;
  if (c.sparse) {
    spec.block_fill = 0.0;
    spec.scattered_voxels = 12;
    spec.scans = 0;
  }
  OccupancyMap map = test::random_map(spec);
  const double half = map.grid().half_extent();
  std::mt19937 rng(c.seed + 7);
  const auto rows = static_cast<int>(map.grid().keys_per_axis());
  std::uniform_int_distribution<int> row(0, rows - 1);
  std::uniform_real_distribution<double> inside(0.05, 0.95);
  // A bound on a voxel face, or inside a voxel.
  auto bound = [&](bool on_face) {
    const double face = double(row(rng) - rows / 2) * kResolution;
    return on_face ? face : face + inside(rng) * kResolution;
  };
  std::array<int, 3> seen{};  // occupied, free, unknown cells compared
  for (const Thresholds thresholds : {Thresholds{0.5, 0.5}, Thresholds{0.62, 0.4}}) {
    map.set_thresholds(thresholds);
    const test::DenseValues dense(map);
    std::vector<std::pair<double, double>> bands = {
        {-half - 1.0, half + 1.0},                  // the whole map: cut to it
        {0.0, kResolution},                         // two rows: z_max on a face takes the row above
        {0.0, kResolution * 0.5},                   // one row
        {kResolution * 0.25, kResolution * 0.75}};  // inside one voxel
    for (int i = 0; i < 8; ++i) {
      double a = bound(i % 2 == 0), b = bound(i % 4 < 2);
      if (a == b) b += kResolution * 0.5;
      bands.emplace_back(std::min(a, b), std::max(a, b));
    }
    for (const auto& [z_min, z_max] : bands) {
      for (const int depth : {0, 1, 2}) {
        for (const ProjectionRule rule : {ProjectionRule::all_known, ProjectionRule::any_free}) {
          const ProjectionOptions options{z_min, z_max, depth, rule};
          SCOPED_TRACE(describe(options) + " thresholds " + std::to_string(thresholds.free));
          const NavigationGrid got = project_to_grid(map, options);
          const NavigationGrid want = brute_force(map, dense, options);
          ASSERT_EQ(got.width, want.width);
          ASSERT_EQ(got.height, want.height);
          EXPECT_EQ(got.origin_x, want.origin_x);
          EXPECT_EQ(got.origin_y, want.origin_y);
          EXPECT_EQ(got.resolution, want.resolution);
          ASSERT_EQ(got.cells.size(), std::size_t{got.width} * got.height);
          for (std::size_t k = 0; k < want.cells.size(); ++k) {
            ASSERT_EQ(got.cells[k], want.cells[k]) << "cell " << k % want.width << ", " << k / want.width;
            ++seen[want.cells[k] == GridCell::occupied ? 0 : want.cells[k] == GridCell::free ? 1 : 2];
          }
        }
      }
    }
  }
  // Every answer must have occurred, or the comparison proves little.
  const int enough = c.sparse ? 5 : 100;
  EXPECT_GT(seen[0], enough);
  EXPECT_GT(seen[1], enough);
  EXPECT_GT(seen[2], enough);
}

INSTANTIATE_TEST_SUITE_P(Maps, NavigationGridBruteForce,
                         testing::Values(Config{4, true, 11}, Config{5, true, 12}, Config{5, false, 13},
                                         Config{6, true, 14}, Config{6, false, 15}, Config{6, true, 16, true},
                                         Config{6, false, 17, true}),
                         [](const testing::TestParamInfo<Config>& param_info) {
                           return "levels" + std::to_string(param_info.param.depth_levels) +
                                  (param_info.param.auto_prune ? "_pruned" : "_unpruned") + "_seed" +
                                  std::to_string(param_info.param.seed) + (param_info.param.sparse ? "_sparse" : "");
                         });

TEST(NavigationGrid, ExtentIsTheKnownPartOfTheBandAndCoarseCellsMergeFineOnes) {
  OccupancyMap map(kResolution, 8);
  // A free 2 x 1 patch at z row 0 and an occupied voxel two columns away, higher up.
  map.update_miss({0.01, 0.01, 0.01});
  map.update_miss({0.135, 0.01, 0.01});
  map.update_hit({0.385, 0.01, 0.3});
  ProjectionOptions low{0.0, 0.1};
  NavigationGrid grid = project_to_grid(map, low);
  ASSERT_EQ(grid.width, 2u);
  ASSERT_EQ(grid.height, 1u);
  EXPECT_EQ(grid.origin_x, 0.0);
  EXPECT_EQ(grid.origin_y, 0.0);
  EXPECT_EQ(grid.at(0, 0), GridCell::free);
  EXPECT_EQ(grid.at(1, 0), GridCell::free);

  // The band reaches the occupied voxel's row: the extent grows to it; the
  // column between is unknown.
  const ProjectionOptions tall{0.0, 0.3, 0, ProjectionRule::any_free};
  grid = project_to_grid(map, tall);
  ASSERT_EQ(grid.width, 4u);
  EXPECT_EQ(grid.at(0, 0), GridCell::free);
  EXPECT_EQ(grid.at(2, 0), GridCell::unknown);
  EXPECT_EQ(grid.at(3, 0), GridCell::occupied);
  // all_known: the free columns hold unknown voxels in the rows above.
  grid = project_to_grid(map, {0.0, 0.3, 0, ProjectionRule::all_known});
  EXPECT_EQ(grid.at(0, 0), GridCell::unknown);

  // Depth 1: cells of 2 x 2 columns; the free patch is one cell, with unknown columns beside it.
  grid = project_to_grid(map, {0.0, 0.1, 1, ProjectionRule::any_free});
  ASSERT_EQ(grid.width, 1u);
  EXPECT_EQ(grid.resolution, 2 * kResolution);
  EXPECT_EQ(grid.at(0, 0), GridCell::free);
  grid = project_to_grid(map, {0.0, 0.1, 1, ProjectionRule::all_known});
  EXPECT_EQ(grid.at(0, 0), GridCell::unknown);

  // Nothing known in the band: the empty grid.
  grid = project_to_grid(map, {1.0, 2.0});
  EXPECT_TRUE(grid.empty());
  EXPECT_EQ(grid.width, 0u);
}

TEST(NavigationGrid, AGridBeyondTheMemoryLimitIsRefusedBeforeItIsAllocated) {
  OccupancyMap map(kResolution, 12);
  map.update_miss({-100.0, -100.0, 0.5});
  map.update_miss({100.0, 100.0, 0.5});  // 1,601 x 1,601 cells apart
  const std::uint64_t saved = memory_limit();
  set_memory_limit(4'000'000);
  try {
    (void)project_to_grid(map, {0.0, 1.0});
    ADD_FAILURE() << "a 5 MB grid was made under a 4 MB limit";
  } catch (const MemoryLimitError& e) {
    EXPECT_NE(std::string(e.what()).find("project_to_grid: a grid of 1601 x 1601 cells needs"), std::string::npos)
        << e.what();
  }
  set_memory_limit(saved);
  EXPECT_EQ(project_to_grid(map, {0.0, 1.0}).width, 1601u);
}

TEST(NavigationGrid, BadOptionsAreRefusedNamingTheValue) {
  const OccupancyMap map(kResolution, 5);  // spans [-2, 2)
  auto message = [&](const ProjectionOptions& options) {
    try {
      (void)project_to_grid(map, options);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({1.0, 1.0}).find("z_min must be below z_max, got z_min 1 and z_max 1"), std::string::npos);
  EXPECT_NE(message({1.0, 0.5}).find("z_min must be below z_max"), std::string::npos);
  EXPECT_NE(message({std::nan(""), 0.5}).find("z_min must be a finite height"), std::string::npos);
  EXPECT_NE(message({0.0, INFINITY}).find("z_max must be a finite height"), std::string::npos);
  EXPECT_NE(message({0.0, 1.0, -1}).find("depth must be >= 0, got -1"), std::string::npos);
  EXPECT_NE(message({0.0, 1.0, 6}).find("depth must be at most the map's depth_levels 5, got 6"), std::string::npos);
  EXPECT_NE(message({2.0, 3.0}).find("lies outside the map, which spans z from -2 to 2"), std::string::npos);
  EXPECT_NE(message({-5.0, -2.01}).find("lies outside the map"), std::string::npos);
  EXPECT_THROW((void)project_to_grid(map, {3.0, 4.0}), std::out_of_range);
  EXPECT_THROW((void)project_to_grid(map, {1.0, 0.0}), std::invalid_argument);
  EXPECT_EQ(parse_projection_rule("any_free"), ProjectionRule::any_free);
  EXPECT_EQ(parse_projection_rule("all_known"), ProjectionRule::all_known);
  try {
    (void)parse_projection_rule("most_free");
    ADD_FAILURE() << "an unknown rule was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown projection rule 'most_free' (the rules: all_known, any_free)");
  }
}

}  // namespace
}  // namespace umbra
