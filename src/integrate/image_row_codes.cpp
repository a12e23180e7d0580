#include "integrate/image_row_codes.hpp"

#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include "core/voxel_code_lanes.hpp"
#include "core/voxel_codes.hpp"

namespace umbra {

void image_row_codes(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                     const Pose& pose, int v, Vec3f* points, std::uint64_t* codes) {
  static const bool avx2 = detail::image_row_codes_avx2_available();  // the CPU does not change
  if (avx2) {
    detail::image_row_codes_avx2(grid, depth, column_factor, row_factor, pose, v, codes);
  } else {
    detail::image_row_codes_plain(grid, depth, column_factor, row_factor, pose, v, points, codes);
  }
}

namespace detail {

void image_row_codes_plain(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                           const Pose& pose, int v, Vec3f* points, std::uint64_t* codes) {
  const std::size_t width = static_cast<std::size_t>(depth.width());
  const std::size_t row = static_cast<std::size_t>(v) * width;
  for (std::size_t u = 0; u < width; ++u) {
    const double z = depth.depth(row + u);
    points[u] = pose.apply(column_factor[u] * z, row_factor * z, z);
  }
  voxel_codes(grid, std::span<const Vec3f>(points, width), codes);
  for (std::size_t u = 0; u < width; ++u) {
    if (depth.depth(row + u) == 0.0) codes[u] = kNoReadingCode;
  }
}

#if UMBRA_VOXEL_CODE_LANES

bool image_row_codes_avx2_available() { return voxel_codes_avx2_available(); }

namespace {

/// One map coordinate of four points: float(((m0 x + m1 y) + m2 z) + m3),
/// Pose::apply's expression in its order (separate multiplies and adds:
/// the build forbids contraction into FMA, and no FMA is enabled here).
__attribute__((target("avx2"))) __m128 map_axis(const double* m, __m256d x, __m256d y, __m256d z) {
  __m256d sum = _mm256_mul_pd(_mm256_set1_pd(m[0]), x);
  sum = _mm256_add_pd(sum, _mm256_mul_pd(_mm256_set1_pd(m[1]), y));
  sum = _mm256_add_pd(sum, _mm256_mul_pd(_mm256_set1_pd(m[2]), z));
  sum = _mm256_add_pd(sum, _mm256_set1_pd(m[3]));
  return _mm256_cvtpd_ps(sum);  // round to nearest, as static_cast<float>
}

}  // namespace

__attribute__((target("avx2"))) void image_row_codes_avx2(const Grid& grid, const DepthImage& depth,
                                                           const double* column_factor, double row_factor,
                                                           const Pose& pose, int v, std::uint64_t* codes) {
  const std::size_t width = static_cast<std::size_t>(depth.width());
  const std::size_t row = static_cast<std::size_t>(v) * width;
  const __m256d inverse_resolution = _mm256_set1_pd(grid.inverse_resolution());
  const __m256d offset = _mm256_set1_pd(double(grid.key_offset()));
  const __m256d rows = _mm256_set1_pd(row_factor);
  const bool raw = depth.is_raw();
  const std::uint16_t* const raw_depths = raw ? depth.raw_depths().data() + row : nullptr;
  const float* const metres = raw ? nullptr : depth.metre_depths().data() + row;
  const __m256d scale = _mm256_set1_pd(depth.metres_per_unit());
  const __m256i no_reading = _mm256_set1_epi64x(static_cast<long long>(kNoReadingCode));
  std::size_t u = 0;
  for (; u + 4 <= width; u += 4) {
    __m256d z;
    __m256d none;  // all-ones lanes for the pixels without a reading (a depth of 0)
    if (raw) {
      // DepthImage::depth: raw * metres_per_unit, the integer exact in a double.
      const __m128i four = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(raw_depths + u));
      z = _mm256_mul_pd(_mm256_cvtepi32_pd(_mm_cvtepu16_epi32(four)), scale);
      none = _mm256_cmp_pd(z, _mm256_setzero_pd(), _CMP_EQ_OQ);
    } else {
      // DepthImage::depth: the reading where 0 < z < infinity, else 0.
      const __m256d d = _mm256_cvtps_pd(_mm_loadu_ps(metres + u));
      const __m256d valid = _mm256_and_pd(_mm256_cmp_pd(d, _mm256_setzero_pd(), _CMP_GT_OQ),
                                          _mm256_cmp_pd(d, _mm256_set1_pd(__builtin_inf()), _CMP_LT_OQ));
      z = _mm256_and_pd(d, valid);
      none = _mm256_cmp_pd(z, _mm256_setzero_pd(), _CMP_EQ_OQ);
    }
    const __m256d x = _mm256_mul_pd(_mm256_loadu_pd(column_factor + u), z);
    const __m256d y = _mm256_mul_pd(rows, z);
    const __m128 px = map_axis(pose.m[0].data(), x, y, z);
    const __m128 py = map_axis(pose.m[1].data(), x, y, z);
    const __m128 pz = map_axis(pose.m[2].data(), x, y, z);
    const __m256i code = lanes::codes(px, py, pz, inverse_resolution, offset);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(codes + u),
                        _mm256_blendv_epi8(code, no_reading, _mm256_castpd_si256(none)));
  }
  for (; u < width; ++u) {
    const double z = depth.depth(row + u);
    const Vec3f point = pose.apply(column_factor[u] * z, row_factor * z, z);
    voxel_codes_scalar(grid, std::span<const Vec3f>(&point, 1), codes + u);
    if (z == 0.0) codes[u] = kNoReadingCode;
  }
}

#else

bool image_row_codes_avx2_available() { return false; }

void image_row_codes_avx2(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                          const Pose& pose, int v, std::uint64_t* codes) {
  std::vector<Vec3f> points(static_cast<std::size_t>(depth.width()));
  image_row_codes_plain(grid, depth, column_factor, row_factor, pose, v, points.data(), codes);
}

#endif

}  // namespace detail
}  // namespace umbra
