// voxel_code_lanes: the codes of four points held in SSE registers, with
// AVX2 (the step of voxel_codes_avx2, shared with the depth images' front
// end, which computes its points in registers and never stores them).
//
// Only for code compiled with target("avx2") that runs after
// detail::voxel_codes_avx2_available(). Every step is the portable code's
// arithmetic on four lanes, so the codes are the same bit for bit: the
// coordinate as a double times the inverse resolution (a plain multiply:
// the build forbids contraction into FMA), the same range test (NaN fails
// it), floor, plus the key offset, and the Morton spread with the same
// masks on 64-bit lanes (not BMI2 pdep: it is microcoded, hundreds of
// cycles, on AMD CPUs before Zen 3).
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define UMBRA_VOXEL_CODE_LANES 1
#include <immintrin.h>

#include "core/voxel_codes.hpp"

namespace umbra::detail::lanes {

/// morton::spread on four 64-bit lanes (each below 2^21).
__attribute__((target("avx2"))) inline __m256i spread(__m256i x) {
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
__attribute__((target("avx2"))) inline __m256i axis_keys(__m128 coordinates, __m256d inverse_resolution,
                                                        __m256d offset, __m256d& inside, __m256d& finite) {
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

/// The codes of the four points (x[i], y[i], z[i]): voxel_codes' answers,
/// kNonFiniteCode and kOutsideCode included.
__attribute__((target("avx2"))) inline __m256i codes(__m128 x, __m128 y, __m128 z, __m256d inverse_resolution,
                                                    __m256d offset) {
  __m256d inside_x, inside_y, inside_z, finite_x, finite_y, finite_z;
  const __m256i kx = axis_keys(x, inverse_resolution, offset, inside_x, finite_x);
  const __m256i ky = axis_keys(y, inverse_resolution, offset, inside_y, finite_y);
  const __m256i kz = axis_keys(z, inverse_resolution, offset, inside_z, finite_z);
  __m256i code = _mm256_or_si256(spread(kx), _mm256_slli_epi64(spread(ky), 1));
  code = _mm256_or_si256(code, _mm256_slli_epi64(spread(kz), 2));
  const __m256d inside = _mm256_and_pd(_mm256_and_pd(inside_x, inside_y), inside_z);
  const __m256d finite = _mm256_and_pd(_mm256_and_pd(finite_x, finite_y), finite_z);
  code = _mm256_blendv_epi8(_mm256_set1_epi64x(static_cast<long long>(kOutsideCode)), code,
                            _mm256_castpd_si256(inside));
  return _mm256_blendv_epi8(_mm256_set1_epi64x(static_cast<long long>(kNonFiniteCode)), code,
                            _mm256_castpd_si256(finite));  // not finite wins
}

}  // namespace umbra::detail::lanes

#endif
