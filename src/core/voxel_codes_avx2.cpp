// voxel_codes with AVX2, four points per step (see voxel_codes.hpp).
//
// Only the functions below are compiled for AVX2 (a target attribute, not a
// flag for the whole file or library), and voxel_codes calls them only when
// the CPU reports AVX2: the library stays runnable on baseline x86-64.
// Every step is the portable code's arithmetic on four lanes, so the codes
// are the same bit for bit: the coordinate as a double times the inverse
// resolution (a plain multiply: the build forbids contraction into FMA),
// the same range test (NaN fails it), floor, plus the key offset, and the
// Morton spread with the same masks on 64-bit lanes (not BMI2 pdep: it is
// microcoded, hundreds of cycles, on AMD CPUs before Zen 3).
#include "core/voxel_codes.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define UMBRA_VOXEL_CODES_AVX2 1
#include <immintrin.h>
#endif

namespace umbra::detail {

#if UMBRA_VOXEL_CODES_AVX2

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "points are read as packed x, y, z floats");

bool voxel_codes_avx2_available() {
  __builtin_cpu_init();  // may run before the constructors that set up __builtin_cpu_supports
  return __builtin_cpu_supports("avx2") != 0;
}

namespace {

/// morton::spread on four 64-bit lanes (each below 2^21).
__attribute__((target("avx2"))) __m256i spread_lanes(__m256i x) {
  x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 32)), _mm256_set1_epi64x(0x001F00000000FFFFLL));
  x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 16)), _mm256_set1_epi64x(0x001F0000FF0000FFLL));
  x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 8)), _mm256_set1_epi64x(0x100F00F00F00F00FLL));
  x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 4)), _mm256_set1_epi64x(0x10C30C30C30C30C3LL));
  x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 2)), _mm256_set1_epi64x(0x1249249249249249LL));
  return x;
}

/// One axis of four points: the key as four 64-bit lanes (unspecified where
/// the coordinate is outside the map), all-ones lanes in `inside` where it
/// is inside and in `finite` where it is finite.
__attribute__((target("avx2"))) __m256i axis_keys(__m128 coordinates, __m256d inverse_resolution, __m256d offset,
                                                 __m256d& inside, __m256d& finite) {
  const __m256d c = _mm256_cvtps_pd(coordinates);  // exact, as the scalar code's Vec3d(p)
  const __m256d magnitude = _mm256_andnot_pd(_mm256_set1_pd(-0.0), c);
  finite = _mm256_cmp_pd(magnitude, _mm256_set1_pd(__builtin_inf()), _CMP_LT_OQ);  // NaN: false
  const __m256d scaled = _mm256_mul_pd(inverse_resolution, c);
  // Grid::axis_key's test: -offset <= scaled < offset, false for NaN.
  inside = _mm256_and_pd(_mm256_cmp_pd(scaled, _mm256_sub_pd(_mm256_setzero_pd(), offset), _CMP_GE_OQ),
                         _mm256_cmp_pd(scaled, offset, _CMP_LT_OQ));
  // floor(scaled) + offset is an integer in [0, 2^21) inside: exact in a
  // double and in an int32.
  const __m256d key = _mm256_add_pd(_mm256_floor_pd(scaled), offset);
  return _mm256_cvtepu32_epi64(_mm256_cvttpd_epi32(key));
}

}  // namespace

__attribute__((target("avx2"))) void voxel_codes_avx2(const Grid& grid, std::span<const Vec3f> points,
                                                       std::uint64_t* codes) {
  const __m256d inverse_resolution = _mm256_set1_pd(grid.inverse_resolution());
  const __m256d offset = _mm256_set1_pd(double(grid.key_offset()));
  const __m256i non_finite_code = _mm256_set1_epi64x(static_cast<long long>(kNonFiniteCode));
  const __m256i outside_code = _mm256_set1_epi64x(static_cast<long long>(kOutsideCode));
  const std::size_t count = points.size();
  std::size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    // Four points are 12 packed floats: a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3.
    const float* f = &points[i].x;
    const __m128 a = _mm_loadu_ps(f);
    const __m128 b = _mm_loadu_ps(f + 4);
    const __m128 c = _mm_loadu_ps(f + 8);
    const __m128 x = _mm_shuffle_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 3, 0, 0)),
                                    _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)), _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 y = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)),
                                    _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 z = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)),
                                    _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)), _MM_SHUFFLE(2, 0, 2, 0));
    __m256d inside_x, inside_y, inside_z, finite_x, finite_y, finite_z;
    const __m256i kx = axis_keys(x, inverse_resolution, offset, inside_x, finite_x);
    const __m256i ky = axis_keys(y, inverse_resolution, offset, inside_y, finite_y);
    const __m256i kz = axis_keys(z, inverse_resolution, offset, inside_z, finite_z);
    __m256i code = _mm256_or_si256(spread_lanes(kx), _mm256_slli_epi64(spread_lanes(ky), 1));
    code = _mm256_or_si256(code, _mm256_slli_epi64(spread_lanes(kz), 2));
    const __m256d inside = _mm256_and_pd(_mm256_and_pd(inside_x, inside_y), inside_z);
    const __m256d finite = _mm256_and_pd(_mm256_and_pd(finite_x, finite_y), finite_z);
    code = _mm256_blendv_epi8(outside_code, code, _mm256_castpd_si256(inside));
    code = _mm256_blendv_epi8(non_finite_code, code, _mm256_castpd_si256(finite));  // not finite wins
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(codes + i), code);
  }
  voxel_codes_scalar(grid, points.subspan(i), codes + i);
}

#else

bool voxel_codes_avx2_available() { return false; }

void voxel_codes_avx2(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes) {
  voxel_codes_scalar(grid, points, codes);
}

#endif

}  // namespace umbra::detail
