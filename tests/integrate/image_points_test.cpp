// A depth image's points found band by band on several workers are the ones
// the public back_project gives, in the same order, with their own voxel
// codes and colors, and the hit voxels are the sorted distinct voxels of
// those points, whatever the number of workers.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/thread_pool.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/image_points.hpp"
#include "integrate/image_row_codes.hpp"
#include "umbra/core/morton.hpp"

namespace umbra {
namespace {

struct Frame {
  int width = 97;  // odd sizes: bands of unequal rows
  int height = 61;
  std::vector<float> metres;
  std::vector<std::uint16_t> raw;
  std::vector<Rgb> colors;
};

Frame random_frame(unsigned seed, int width = 97, int height = 61) {
  Frame f;
  f.width = width;
  f.height = height;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> depth(0.3f, 6.0f);
  const std::size_t n = std::size_t(f.width) * std::size_t(f.height);
  for (std::size_t i = 0; i < n; ++i) {
    // A smooth surface (neighbouring pixels share voxels), holes, scattered
    // readings and a few beyond the map (outside its keys).
    const double u = double(i % std::size_t(f.width));
    const double v = double(i / std::size_t(f.width));
    float z = static_cast<float>(2.0 + 0.5 * std::sin(u / 9.0) + 0.3 * std::cos(v / 7.0));
    if (rng() % 7 == 0) z = 0.0f;
    if (rng() % 13 == 0) z = depth(rng);
    if (rng() % 211 == 0) z = 4000.0f;
    f.metres.push_back(z);
    f.raw.push_back(static_cast<std::uint16_t>(std::min(z, 12.0f) * 5000.0f));
    f.colors.push_back(Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i >> 8), 7});
  }
  return f;
}

TEST(ImagePoints, AnyNumberOfWorkersGivesBackProjectsPointsAndTheirVoxels) {
  const Grid grid(0.1, 15);  // +- 1638 m: 4000 m lies outside
  const PinholeCamera camera{60.0, 55.0, 48.3, 30.1};
  const Pose pose = Pose::from_translation_quaternion(0.5, -1.25, 0.75, 0.5, -0.5, 0.5, -0.5);
  // Also a wide image: its bands are back-projected a few rows at a time
  // when only the voxels are kept (about 10,000 pixels a time).
  for (const Frame& f : {random_frame(5), random_frame(6, 2500, 11)}) {
    for (const bool raw : {false, true}) {
      const DepthImage image = raw ? DepthImage::raw(f.raw, f.width, f.height, 5000.0)
                                   : DepthImage::metres(f.metres, f.width, f.height);
      std::vector<Vec3f> expected_points;
      std::vector<std::uint32_t> expected_pixels;
      back_project(image, camera, pose, expected_points, &expected_pixels);
      ASSERT_GT(expected_points.size(), 1000u);
      std::vector<std::uint64_t> expected_voxels;
      std::size_t outside = 0;
      for (const Vec3f& p : expected_points) {
        if (const auto key = grid.key_checked(p)) {
          expected_voxels.push_back(morton::encode(*key));
        } else {
          ++outside;
        }
      }
      std::sort(expected_voxels.begin(), expected_voxels.end());
      expected_voxels.erase(std::unique(expected_voxels.begin(), expected_voxels.end()), expected_voxels.end());
      if (!raw) {
        ASSERT_GT(outside, 0u);  // raw depths stop at 13 m
      }
      // Voxels shared by pixels (the wide image's far columns spread wider).
      const std::size_t pixels_a_voxel = f.width > 1000 ? 1 : 2;
      ASSERT_LT(pixels_a_voxel * expected_voxels.size(), expected_points.size());

      for (const unsigned threads : {1u, 2u, 3u, 8u}) {
        SCOPED_TRACE(std::string(raw ? "raw" : "metres") + ", threads " + std::to_string(threads));
        ThreadPool pool(threads);
        ImagePoints found;
        std::atomic<int> alongside_runs{0};
        found.build(grid, image, camera, pose, f.colors, threads > 1 ? &pool : nullptr, [&] { ++alongside_runs; });
        EXPECT_EQ(alongside_runs.load(), 1);
        ASSERT_EQ(found.points().size(), expected_points.size());
        bool same_points = true;
        for (std::size_t i = 0; i < expected_points.size(); ++i) {
          same_points = same_points && found.points()[i] == expected_points[i] && found.pixels()[i] == expected_pixels[i];
          same_points = same_points && found.colors()[i] == f.colors[expected_pixels[i]];
          const auto key = grid.key_checked(expected_points[i]);
          same_points = same_points && found.codes()[i] == (key ? morton::encode(*key) : kOutsideCode);
        }
        EXPECT_TRUE(same_points);
        std::vector<std::uint64_t> voxels;
        found.for_each_voxel([&](std::uint64_t code) { voxels.push_back(code); });
        EXPECT_TRUE(voxels == expected_voxels);
        // Without colors: the same points and voxels, no codes kept.
        ImagePoints plain;
        plain.build(grid, image, camera, pose, {}, threads > 1 ? &pool : nullptr, [] {});
        EXPECT_TRUE(plain.codes().empty() && plain.colors().empty());
        EXPECT_TRUE(std::equal(plain.points().begin(), plain.points().end(), expected_points.begin(), expected_points.end()));
        voxels.clear();
        plain.for_each_voxel([&](std::uint64_t code) { voxels.push_back(code); });
        EXPECT_TRUE(voxels == expected_voxels);
        EXPECT_EQ(found.out_of_bounds(), outside);
        EXPECT_EQ(found.non_finite(), 0u);
        // Voxels only (the projective integrator without colors): the same
        // voxels and counts from rows back-projected a few at a time, no points
        // kept; the object that held this image's points before.
        alongside_runs = 0;
        found.build(grid, image, camera, pose, {}, threads > 1 ? &pool : nullptr, [&] { ++alongside_runs; },
                    /*voxels_only=*/true);
        EXPECT_EQ(alongside_runs.load(), 1);
        EXPECT_TRUE(found.points().empty() && found.pixels().empty() && found.codes().empty() && found.colors().empty());
        voxels.clear();
        found.for_each_voxel([&](std::uint64_t code) { voxels.push_back(code); });
        EXPECT_TRUE(voxels == expected_voxels);
        EXPECT_EQ(found.out_of_bounds(), outside);
        EXPECT_EQ(found.non_finite(), 0u);
      }
    }
  }
}

// A code range's voxels (a walk task's subtree, or any range) are the
// image's voxels in that range, in code order, each once, whatever the number
// of bands merged: up to 2 a worker, and past the 64 that for_each_voxel_in
// keeps on the stack (a tall image on 40 workers: 80 bands).
TEST(ImagePoints, TheVoxelsOfACodeRangeAreTheImagesVoxelsInIt) {
  const Grid grid(0.1, 15);
  const PinholeCamera camera{60.0, 55.0, 48.3, 30.1};
  const Pose pose = Pose::from_translation_quaternion(0.5, -1.25, 0.75, 0.5, -0.5, 0.5, -0.5);
  for (const Frame& f : {random_frame(5), random_frame(8, 23, 1400)}) {
    const DepthImage image = DepthImage::metres(f.metres, f.width, f.height);
    std::vector<std::uint64_t> all;
    ImagePoints one_band;
    one_band.build(grid, image, camera, pose, {}, nullptr, [] {}, /*voxels_only=*/true);
    one_band.for_each_voxel([&](std::uint64_t code) { all.push_back(code); });
    ASSERT_GT(all.size(), 500u);
    ASSERT_TRUE(std::is_sorted(all.begin(), all.end()) && std::adjacent_find(all.begin(), all.end()) == all.end());
    // Subtrees of several depths around the image's voxels, and ranges between any two codes.
    std::mt19937 rng(17);
    std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges{{0, ~std::uint64_t{0}}, {all[0], all[0] + 1}};
    for (int i = 0; i < 60; ++i) {
      const std::uint64_t code = all[rng() % all.size()];
      const int depth = static_cast<int>(rng() % 8);
      const std::uint64_t size = std::uint64_t{1} << (3 * depth);
      ranges.emplace_back(code & ~(size - 1), (code & ~(size - 1)) + size);
      const std::uint64_t other = all[rng() % all.size()] + rng() % 3;
      ranges.emplace_back(std::min(code, other), std::max(code, other));
    }
    for (const unsigned threads : {2u, 3u, 8u, 40u}) {
      SCOPED_TRACE("height " + std::to_string(f.height) + ", threads " + std::to_string(threads));
      ThreadPool pool(threads);
      ImagePoints banded;
      banded.build(grid, image, camera, pose, {}, &pool, [] {}, /*voxels_only=*/true);
      for (const auto& [first, end] : ranges) {
        const std::vector<std::uint64_t> expected(std::lower_bound(all.begin(), all.end(), first),
                                                  std::lower_bound(all.begin(), all.end(), end));
        std::vector<std::uint64_t> found;
        banded.for_each_voxel_in(first, end, [&](std::uint64_t code) { found.push_back(code); });
        ASSERT_EQ(found, expected) << "codes [" << first << ", " << end << ")";
      }
    }
  }
}

// The front end's row codes (image_row_codes, AVX2 where the CPU has it, and
// its portable definition) are the codes of back_project's points, pixel by
// pixel, and kNoReadingCode exactly where a pixel has no reading: metre
// depths with NaN, infinities, negatives and zeros, raw depths with zeros,
// points outside the map, rows whose width is no multiple of four. On a grid
// of 0.1 mm, 70 m from the origin, a voxel holds a dozen float coordinates,
// so a point rounded differently (float arithmetic instead of double, say)
// changes its code.
TEST(ImagePoints, RowCodesAreTheCodesOfBackProjectedPoints) {
  const PinholeCamera camera{60.0, 55.0, 48.3, 30.1};
  for (const bool fine : {false, true}) {
    const Grid grid = fine ? Grid(1e-4, 21) : Grid(0.02, 16);  // +- 104 m; +- 655 m
    const Pose pose = Pose::from_translation_quaternion(fine ? 70.0 : 0.5, fine ? -60.0 : -1.25, fine ? 50.0 : 0.75,
                                                        0.5, -0.5, 0.5, -0.5);
    for (const int width : {97, 4, 3}) {
      Frame f = random_frame(11, width, 23);
      std::mt19937 rng(3);
      for (float& z : f.metres) {
        if (rng() % 17 == 0) z = std::numeric_limits<float>::quiet_NaN();
        if (rng() % 19 == 0) z = std::numeric_limits<float>::infinity();
        if (rng() % 23 == 0) z = -z;
      }
      f.metres[1] = 4000.0f;  // outside the map, in the narrow images too
      for (const bool raw : {false, true}) {
        SCOPED_TRACE(std::string(raw ? "raw" : "metres") + ", width " + std::to_string(width) +
                     (fine ? ", fine grid" : ""));
        const DepthImage image = raw ? DepthImage::raw(f.raw, f.width, f.height, 5000.0)
                                     : DepthImage::metres(f.metres, f.width, f.height);
        std::vector<Vec3f> points;
        std::vector<std::uint32_t> pixels;
        back_project(image, camera, pose, points, &pixels);
        std::vector<std::uint64_t> expected(image.pixel_count(), kNoReadingCode);
        std::vector<std::uint64_t> point_codes(points.size());
        voxel_codes(grid, points, point_codes.data());
        for (std::size_t i = 0; i < points.size(); ++i) expected[pixels[i]] = point_codes[i];
        if (!raw) {
          ASSERT_GT(std::count(expected.begin(), expected.end(), kOutsideCode), 0);  // raw depths stop at 13 m
        }
        ASSERT_GT(std::count_if(expected.begin(), expected.end(), [](std::uint64_t c) { return c < kOutsideCode; }),
                  f.width * 10);
        ASSERT_GT(std::count(expected.begin(), expected.end(), kNoReadingCode), 0);
        std::vector<double> column_factor;
        for (int u = 0; u < f.width; ++u) column_factor.push_back((u - camera.cx) / camera.fx);
        std::vector<Vec3f> scratch(static_cast<std::size_t>(f.width));
        std::vector<std::uint64_t> plain(image.pixel_count());
        std::vector<std::uint64_t> fast(image.pixel_count());
        std::vector<std::uint64_t> vector_lanes(image.pixel_count());
        for (int v = 0; v < f.height; ++v) {
          const double row_factor = (v - camera.cy) / camera.fy;
          const std::size_t row = std::size_t(v) * std::size_t(f.width);
          detail::image_row_codes_plain(grid, image, column_factor.data(), row_factor, pose, v, scratch.data(),
                                        plain.data() + row);
          image_row_codes(grid, image, column_factor.data(), row_factor, pose, v, scratch.data(), fast.data() + row);
          if (detail::image_row_codes_avx2_available()) {
            detail::image_row_codes_avx2(grid, image, column_factor.data(), row_factor, pose, v,
                                         vector_lanes.data() + row);
          }
        }
        EXPECT_TRUE(plain == expected);
        EXPECT_TRUE(fast == expected);
        if (detail::image_row_codes_avx2_available()) {
          EXPECT_TRUE(vector_lanes == expected);
        }
      }
    }
  }
}

}  // namespace
}  // namespace umbra
