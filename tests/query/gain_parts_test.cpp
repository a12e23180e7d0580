// The parts the information gain is built from, each against its plain
// definition: OccupiedBitmap rows against its single bits, ViewImage
// footprints against the projections of points of the box (every point's
// pixel must lie in its box's footprint), and its pyramids against a scan of
// the pixels. FrustumGeometry's block count of voxel centres against
// contains() point by point.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "query/geometry.hpp"
#include "query/occupied_bitmap.hpp"
#include "query/view_image.hpp"

namespace umbra::detail {
namespace {

TEST(OccupiedBitmap, RowsAreTheirBits) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::uint32_t> coordinate(100, 300);
  OccupiedBitmap bitmap;
  bitmap.reset({120, 130, 140}, {270, 180, 190});
  for (int i = 0; i < 40; ++i) {
    Key low{coordinate(rng), coordinate(rng), coordinate(rng)};
    Key high = low;
    for (int a = 0; a < 3; ++a) high[a] += std::uniform_int_distribution<std::uint32_t>(0, 70)(rng);
    bitmap.set_box(low, high);
  }
  for (int i = 0; i < 2000; ++i) {
    const std::int64_t x0 = std::uniform_int_distribution<std::int64_t>(50, 300)(rng);
    const int count = std::uniform_int_distribution<int>(1, 64)(rng);
    const std::int64_t y = std::uniform_int_distribution<std::int64_t>(125, 185)(rng);
    const std::int64_t z = std::uniform_int_distribution<std::int64_t>(135, 195)(rng);
    const std::uint64_t row = bitmap.row(x0, count, y, z);
    for (int b = 0; b < 64; ++b) {
      const bool expected = b < count && bitmap.occupied(x0 + b, y, z);
      ASSERT_EQ((row >> b) & 1u, expected ? 1u : 0u) << "x0 " << x0 << " bit " << b;
    }
  }
  // Outside the box nothing is occupied, whatever was set there.
  EXPECT_FALSE(bitmap.occupied(119, 150, 150));
  EXPECT_FALSE(bitmap.occupied(150, 181, 150));
}

TEST(OccupiedBitmap, SetBoxSetsExactlyItsVoxels) {
  OccupiedBitmap bitmap;
  bitmap.reset({0, 0, 0}, {200, 3, 3});
  bitmap.set_box({60, 1, 2}, {130, 2, 2});  // crosses word borders
  for (std::int64_t x = 0; x <= 200; ++x) {
    for (std::int64_t y = 0; y <= 3; ++y) {
      for (std::int64_t z = 0; z <= 3; ++z) {
        const bool inside = x >= 60 && x <= 130 && y >= 1 && y <= 2 && z == 2;
        ASSERT_EQ(bitmap.occupied(x, y, z), inside) << x << " " << y << " " << z;
      }
    }
  }
}

ViewImage::Setup test_setup() {
  ViewImage::Setup setup;
  setup.apex = {0.3, -0.2, 0.1};
  const double yaw = 0.6;
  const double pitch = -0.3;
  setup.f = {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
  setup.l = {-std::sin(yaw), std::cos(yaw), 0.0};
  setup.u = {setup.f.y * setup.l.z - setup.f.z * setup.l.y, setup.f.z * setup.l.x - setup.f.x * setup.l.z,
             setup.f.x * setup.l.y - setup.f.y * setup.l.x};
  setup.half_width = 1.6;
  setup.half_height = 0.7;
  setup.pixel = 0.05;
  setup.near_plane = 1e-3;
  setup.candidates = true;
  return setup;
}

TEST(ViewImage, EveryPointOfABoxFallsInItsFootprint) {
  ViewImage image;
  image.reset(test_setup());
  const Vec3d apex = image.setup().apex;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0;
  for (int i = 0; i < 300; ++i) {
    // Boxes around the view, some reaching behind the sensor plane.
    const Vec3d low{apex.x - 2.0 + 6.0 * unit(rng), apex.y - 3.0 + 6.0 * unit(rng), apex.z - 2.0 + 4.0 * unit(rng)};
    const Vec3d size{0.05 + 1.5 * unit(rng), 0.05 + 1.5 * unit(rng), 0.05 + 1.5 * unit(rng)};
    const Aabb box{low, low + size};
    PixelRect rect{};
    bool clipped = false;
    const bool any = image.footprint(box, rect, clipped);
    for (int j = 0; j < 200; ++j) {
      const Vec3d p{low.x + size.x * unit(rng), low.y + size.y * unit(rng), low.z + size.z * unit(rng)};
      int px = 0;
      int py = 0;
      if (!image.pixel_of(p - apex, px, py)) continue;  // behind the near plane or off the image
      ASSERT_TRUE(any) << "a point of the box is in the image but the box has no footprint";
      EXPECT_TRUE(px >= rect.x0 && px <= rect.x1 && py >= rect.y0 && py <= rect.y1);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(ViewImage, PyramidsAndCandidatesFollowTheDraws) {
  ViewImage image;
  image.reset(test_setup());
  std::mt19937 rng(7);
  std::vector<float> nearest(std::size_t(image.width()) * std::size_t(image.height()),
                             std::numeric_limits<float>::infinity());
  std::vector<int> drawn(nearest.size(), 0);
  for (std::uint32_t i = 0; i < 200; ++i) {
    std::uniform_int_distribution<int> x(0, image.width() - 1);
    std::uniform_int_distribution<int> y(0, image.height() - 1);
    int x0 = x(rng);
    int x1 = x(rng);
    int y0 = y(rng);
    int y1 = y(rng);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    const double near = std::uniform_real_distribution<double>(0.1, 9.0)(rng);
    image.draw({x0, y0, x1, y1}, near, i);
    for (int py = y0; py <= y1; ++py) {
      for (int px = x0; px <= x1; ++px) {
        const std::size_t k = std::size_t(py) * std::size_t(image.width()) + std::size_t(px);
        nearest[k] = std::min(nearest[k], static_cast<float>(near));
        ++drawn[k];
      }
    }
  }
  image.finish();
  for (int py = 0; py < image.height(); ++py) {
    for (int px = 0; px < image.width(); ++px) {
      const std::size_t k = std::size_t(py) * std::size_t(image.width()) + std::size_t(px);
      // Distances are rounded down to float, never up.
      EXPECT_LE(image.nearest(px, py), nearest[k]);
      EXPECT_GE(image.nearest(px, py), std::nextafter(nearest[k], 0.0f));
      int count = 0;
      bool overflow = false;
      const ViewImage::Candidate* list = image.candidates(px, py, count, overflow);
      EXPECT_EQ(count, std::min(drawn[k], ViewImage::kCandidates));
      EXPECT_EQ(overflow, drawn[k] > ViewImage::kCandidates);
      for (int c = 1; c < count; ++c) EXPECT_LE(list[c - 1].near, list[c].near);
      if (count > 0) {
        EXPECT_EQ(list[0].near, image.nearest(px, py));
      }
    }
  }
  // Rectangles: the pyramids bound the least and greatest pixel from the
  // right side (they may read a few pixels more).
  for (int i = 0; i < 500; ++i) {
    std::uniform_int_distribution<int> x(0, image.width() - 1);
    std::uniform_int_distribution<int> y(0, image.height() - 1);
    PixelRect rect{x(rng), y(rng), 0, 0};
    rect.x1 = std::min(image.width() - 1, rect.x0 + std::uniform_int_distribution<int>(0, 20)(rng));
    rect.y1 = std::min(image.height() - 1, rect.y0 + std::uniform_int_distribution<int>(0, 20)(rng));
    float least = std::numeric_limits<float>::infinity();
    float greatest = -std::numeric_limits<float>::infinity();
    for (int py = rect.y0; py <= rect.y1; ++py) {
      for (int px = rect.x0; px <= rect.x1; ++px) {
        least = std::min(least, image.nearest(px, py));
        greatest = std::max(greatest, image.nearest(px, py));
      }
    }
    EXPECT_LE(image.nearest(rect), least);
    EXPECT_GE(image.nearest_in_every_pixel(rect), greatest);
  }
}

/// Whether `frustum` holds (xs[i], ys[j], zs[k]), point by point: the definition.
int count_one_by_one(const FrustumGeometry& frustum, const double* xs, const double* ys, const double* zs, int n) {
  int count = 0;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const bool inside = frustum.contains({xs[i], ys[j], zs[k]});
        EXPECT_EQ(frustum.contains_quickly({xs[i], ys[j], zs[k]}), inside);
        count += inside ? 1 : 0;
      }
    }
  }
  return count;
}

TEST(FrustumGeometry, BlockCountsEqualContainsPointByPoint) {
  // Blocks of grid points around frustums whose origin is a grid point, so
  // that points lie exactly on the side planes (yaw 0 or 45 degrees, fields
  // of view of 90 degrees) and exactly at max_range or min_range (3-4-5
  // triangles), besides random ones.
  const double step = 0.1;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int counted = 0;
  int blocks_across = 0;
  for (int f = 0; f < 60; ++f) {
    const bool on_grid = f % 2 == 0;
    const Vec3d origin = on_grid ? Vec3d{0.0, 0.0, 0.0} : Vec3d{unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5};
    const double yaw = on_grid ? 45.0 * (f % 8 / 2) : 360.0 * unit(rng);
    const double pitch = on_grid ? 0.0 : 60.0 * unit(rng) - 30.0;
    const double hfov = on_grid ? 90.0 : 20.0 + 150.0 * unit(rng);
    const double vfov = on_grid ? 90.0 : 20.0 + 140.0 * unit(rng);
    // On the grid, ranges a hair short of the ties too (a centre 0.5 away
    // then lies outside, by less than the margins).
    const double hair = f % 4 == 0 ? 0.0 : 1e-12;
    const double max_range = on_grid ? 0.5 - hair : 0.2 + 0.8 * unit(rng);
    const double min_range = f % 3 == 0 ? (on_grid ? 0.3 + hair : 0.3 * max_range) : 0.0;
    const FrustumGeometry frustum(Frustum::from_degrees(origin, yaw, pitch, hfov, vfov, min_range, max_range));
    if (on_grid) {
      // Every point and 2-block around the origin: the ties at the range
      // (a centre such as (0.3, 0.4, 0) lies a rounding beyond 0.5) and on
      // the planes are met for sure.
      for (const int n : {1, 2}) {
        for (int z = -6; z < 6; z += n) {
          for (int y = -6; y < 6; y += n) {
            for (int x = -6; x < 6; x += n) {
              const std::array<double, 2> xs{double(x) * step, double(x + 1) * step};
              const std::array<double, 2> ys{double(y) * step, double(y + 1) * step};
              const std::array<double, 2> zs{double(z) * step, double(z + 1) * step};
              ASSERT_EQ(frustum.count_grid_points(xs.data(), ys.data(), zs.data(), n),
                        count_one_by_one(frustum, xs.data(), ys.data(), zs.data(), n))
                  << "frustum " << f << " at " << x << " " << y << " " << z << ", " << n << " per edge";
            }
          }
        }
      }
    }
    for (int b = 0; b < 40; ++b) {
      const int n = 1 << std::uniform_int_distribution<int>(0, 3)(rng);
      std::array<double, 8> xs{}, ys{}, zs{};
      std::array<int, 3> first{};
      for (int& a : first) a = std::uniform_int_distribution<int>(-12, 12 - n)(rng);
      for (int i = 0; i < n; ++i) {
        xs[std::size_t(i)] = double(first[0] + i) * step;
        ys[std::size_t(i)] = double(first[1] + i) * step;
        zs[std::size_t(i)] = double(first[2] + i) * step;
      }
      const int expected = count_one_by_one(frustum, xs.data(), ys.data(), zs.data(), n);
      ASSERT_EQ(frustum.count_grid_points(xs.data(), ys.data(), zs.data(), n), expected)
          << "frustum " << f << " block " << b << " of " << n << " per edge";
      counted += expected;
      blocks_across += expected > 0 && expected < n * n * n ? 1 : 0;
    }
  }
  EXPECT_GT(counted, 1000);
  EXPECT_GT(blocks_across, 100);
}

}  // namespace
}  // namespace umbra::detail
