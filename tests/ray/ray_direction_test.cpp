// octomap_norm_exceeds is octomap_norm(v) > bound, point for point, also
// for vectors within a few float roundings of the bound (where it takes the
// square root) and for zero, infinite and NaN coordinates.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "ray/ray_direction.hpp"

namespace umbra {
namespace {

TEST(RayDirection, NormExceedsIsTheNormComparedWithTheBound) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> exponent(-12.0, -2.0);
  std::size_t near = 0;  // vectors whose squared sum lies within 1e-6 of the bound's square
  std::size_t beyond = 0;
  for (const double bound : {5.0, 0.1, 30.0, 1e-3, 7.25, 123.456}) {
    for (int i = 0; i < 20000; ++i) {
      Vec3d d{unit(rng), unit(rng), unit(rng)};
      const double length = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      if (length < 1e-3) continue;
      // Lengths of bound (1 +- 10^e): from a float rounding or two to 1%.
      const double offset = (i % 2 == 0 ? 1.0 : -1.0) * std::pow(10.0, exponent(rng));
      const double scale = bound * (1.0 + (i % 5 == 0 ? 0.0 : offset)) / length;
      const Vec3f v{static_cast<float>(d.x * scale), static_cast<float>(d.y * scale), static_cast<float>(d.z * scale)};
      const double norm = octomap_norm(v);
      near += std::abs(norm * norm / (bound * bound) - 1.0) < 1e-6 ? 1u : 0u;
      beyond += norm > bound ? 1u : 0u;
      ASSERT_EQ(octomap_norm_exceeds(v, bound), norm > bound) << v.x << " " << v.y << " " << v.z << " bound " << bound;
    }
  }
  EXPECT_GT(near, 10000u);
  EXPECT_GT(beyond, 20000u);
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Vec3f v : {Vec3f{0.0f, 0.0f, 0.0f}, Vec3f{inf, 0.0f, 0.0f}, Vec3f{0.0f, nan, 1.0f}, Vec3f{5.0f, 0.0f, 0.0f},
                        Vec3f{3.0f, 4.0f, 0.0f}}) {
    for (const double bound : {0.0, 5.0}) {
      EXPECT_EQ(octomap_norm_exceeds(v, bound), octomap_norm(v) > bound) << v.x << " " << v.y << " " << v.z;
    }
  }
}

}  // namespace
}  // namespace umbra
