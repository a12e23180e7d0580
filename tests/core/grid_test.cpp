// Grid: the key rule of docs/design.md (Semantics), the map's extent, centres.
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "umbra/core/grid.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

TEST(Grid, KeyIsFloorOfCoordinateOverResolutionPlusOffset) {
  std::mt19937 rng(3);
  for (const int depth_levels : {1, 2, 8, 16, 21}) {
    for (const double resolution : {0.01, 0.05, 0.1, 0.25, 1.0}) {
      const Grid grid(resolution, depth_levels);
      const double half = grid.half_extent();
      std::uniform_real_distribution<double> coordinate(-half, half);
      for (int i = 0; i < 500; ++i) {
        const double c = coordinate(rng);
        const auto key = grid.axis_key(c);
        ASSERT_TRUE(key.has_value()) << c;
        const auto expected = static_cast<std::int64_t>(std::floor(c * (1.0 / resolution))) +
                              (std::int64_t{1} << (depth_levels - 1));
        ASSERT_EQ(*key, expected) << "c=" << c << " res=" << resolution;
      }
    }
  }
}

TEST(Grid, CoordinatesOutsideTheExtentAreRejected) {
  const Grid grid(0.5, 4);  // 16 keys per axis: [-4, 4) metres
  EXPECT_EQ(grid.half_extent(), 4.0);
  EXPECT_TRUE(grid.axis_key(-4.0).has_value());
  EXPECT_EQ(*grid.axis_key(-4.0), 0u);
  EXPECT_EQ(*grid.axis_key(3.999), 15u);
  EXPECT_FALSE(grid.axis_key(4.0).has_value());
  EXPECT_FALSE(grid.axis_key(-4.001).has_value());
  EXPECT_FALSE(grid.axis_key(std::numeric_limits<double>::quiet_NaN()).has_value());
  EXPECT_FALSE(grid.axis_key(std::numeric_limits<double>::infinity()).has_value());
  EXPECT_FALSE(grid.axis_key(1e300).has_value());
  EXPECT_FALSE(grid.key_checked(Vec3d{0, 0, 5}).has_value());
}

TEST(Grid, KeyThrowsWithTheCoordinateAndTheExtent) {
  const Grid grid(0.5, 4);
  try {
    (void)grid.key(Vec3d{1.0, 2.0, 17.25});
    FAIL() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("17.25"), std::string::npos) << message;
    EXPECT_NE(message.find("[-4, 4)"), std::string::npos) << message;
  }
}

// A coordinate refused at the map's edge is printed as the exact value
// tested, and the span exactly too, so that the message never shows a value
// inside the span it says the value is outside of; where the key
// computation (c * (1 / resolution), floored, as OctoMap's) rounds a value
// inside the span to a key outside, the message says so. Issue 21: a ray
// from x = -3276.8 was refused as "(-3276.80005, ...) is outside [-3276.8, 3276.8)".
TEST(Grid, AnEdgeCoordinateIsRefusedWithTheExactValueTestedAndNoContradiction) {
  std::size_t refused = 0;
  std::size_t rounded_outside = 0;
  for (const int depth_levels : {4, 16, 21}) {
    // The last two: found by search, each has a coordinate just below the span's top whose key rounds to 2^15.
    for (const double resolution : {0.1, 0.05, 0.37, 0.3, 0.7, 0.013, 1e-4, 999.9, 0.20996970583824853, 0.89519100837016574}) {
      const Grid grid(resolution, depth_levels);
      const double h = grid.half_extent();
      for (const double edge : {-h, h}) {
        std::vector<double> values;
        double up = edge;
        double down = edge;
        for (int i = 0; i < 40; ++i) {
          values.push_back(up);
          values.push_back(down);
          values.push_back(static_cast<float>(up));  // as the ray walks round them
          up = std::nextafter(up, 1e300);
          down = std::nextafter(down, -1e300);
        }
        for (const double c : values) {
          if (grid.axis_key(c)) continue;
          ++refused;
          std::string message;
          try {
            (void)grid.key(Vec3d{0.0, c, 0.0});
          } catch (const std::out_of_range& e) {
            message = e.what();
          }
          ASSERT_FALSE(message.empty()) << c;
          // "coordinate (X, Y, Z) is outside the map, which spans [LO, HI)"
          double x = 0;
          double y = 0;
          double z = 0;
          double lo = 0;
          double hi = 0;
          ASSERT_EQ(std::sscanf(message.c_str(), "coordinate (%lf, %lf, %lf) is outside the map, which spans [%lf, %lf)",
                                &x, &y, &z, &lo, &hi),
                    5)
              << message;
          EXPECT_EQ(y, c) << "the value tested, to the last bit: " << message;
          EXPECT_EQ(lo, -h) << message;
          EXPECT_EQ(hi, h) << message;
          const bool inside_span = y >= lo && y < hi;
          const bool says_rounded = message.find("y = ") != std::string::npos &&
                                    message.find("rounds outside") != std::string::npos;
          EXPECT_EQ(inside_span, says_rounded) << message;
          rounded_outside += says_rounded;
        }
      }
    }
  }
  EXPECT_GT(refused, 1000u);
  EXPECT_GT(rounded_outside, 0u) << "some resolution should round a value inside the span outside";
}

TEST(Grid, RejectsBadParameters) {
  EXPECT_THROW(Grid(0.0, 16), std::invalid_argument);
  EXPECT_THROW(Grid(-0.1, 16), std::invalid_argument);
  EXPECT_THROW(Grid(std::numeric_limits<double>::quiet_NaN(), 16), std::invalid_argument);
  EXPECT_THROW(Grid(std::numeric_limits<double>::infinity(), 16), std::invalid_argument);
  EXPECT_THROW(Grid(0.1, 0), std::invalid_argument);
  EXPECT_THROW(Grid(0.1, 22), std::invalid_argument);
  EXPECT_NO_THROW(Grid(0.1, 1));
  EXPECT_NO_THROW(Grid(0.1, 21));
}

// Resolutions are physical: 0.1 mm to 1 km, both ends included; the message
// names the range and the value in its shortest exact form (no 309 digits).
TEST(Grid, ResolutionRangeIsEnforcedWithItsBoundsInTheMessage) {
  EXPECT_NO_THROW(Grid(kMinResolution, 21));
  EXPECT_NO_THROW(Grid(kMaxResolution, 21));
  EXPECT_EQ(kMinResolution, 1e-4);
  EXPECT_EQ(kMaxResolution, 1e3);
  const std::vector<std::pair<double, std::string>> cases = {
      {std::nextafter(kMinResolution, 0.0), "got 9.999999999999999e-05"},
      {std::nextafter(kMaxResolution, 2e3), "got 1000.0000000000001"},
      {1e-300, "got 1e-300"},
      {1e300, "got 1e+300"},
      {std::numeric_limits<double>::denorm_min(), "got 5e-324"},
      {-std::numeric_limits<double>::infinity(), "got -inf"},
  };
  for (const auto& [resolution, expected] : cases) {
    try {
      Grid(resolution, 16);
      ADD_FAILURE() << resolution << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("resolution must be a number of metres in [0.0001, 1000] (0.1 mm to 1 km), " + expected),
                std::string::npos)
          << message;
    }
    MapConfig config;
    config.resolution = resolution;
    EXPECT_THROW(config.validate(), std::invalid_argument);
  }
}

TEST(Grid, CentresAndCornersAtEveryDepth) {
  const Grid grid(0.1, 16);
  const Key key = grid.key(Vec3d{0.05, -0.05, 1.234});
  const Vec3d centre = grid.center(key);
  EXPECT_NEAR(centre.x, 0.05, 1e-12);
  EXPECT_NEAR(centre.y, -0.05, 1e-12);
  EXPECT_NEAR(centre.z, 1.25, 1e-12);
  // Depth 2: 0.4 m nodes aligned to multiples of 0.4 m.
  const Vec3d corner = grid.min_corner(key, 2);
  EXPECT_NEAR(corner.x, 0.0, 1e-12);
  EXPECT_NEAR(corner.y, -0.4, 1e-12);
  EXPECT_NEAR(corner.z, 1.2, 1e-12);
  EXPECT_NEAR(grid.center(key, 2).z, 1.4, 1e-12);
  EXPECT_DOUBLE_EQ(grid.node_size(2), 0.4);
  // Every centre maps back to its own key.
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint32_t> any_key(0, grid.keys_per_axis() - 1);
  for (int i = 0; i < 1000; ++i) {
    const Key k{any_key(rng), any_key(rng), any_key(rng)};
    ASSERT_EQ(grid.key(grid.center(k)), k);
  }
}

}  // namespace
}  // namespace umbra
