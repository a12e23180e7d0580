// voxel_codes with AVX2, four points per step (see voxel_codes.hpp; the
// step itself is in voxel_code_lanes.hpp).
//
// Only the functions below are compiled for AVX2 (a target attribute, not a
// flag for the whole file or library), and voxel_codes calls them only when
// the CPU reports AVX2: the library stays runnable on baseline x86-64.
#include "core/voxel_codes.hpp"
#include "core/voxel_code_lanes.hpp"

#if UMBRA_VOXEL_CODE_LANES
#define UMBRA_VOXEL_CODES_AVX2 1
#endif

namespace umbra::detail {

#if UMBRA_VOXEL_CODES_AVX2

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "points are read as packed x, y, z floats");

bool voxel_codes_avx2_available() {
  __builtin_cpu_init();  // may run before the constructors that set up __builtin_cpu_supports
  return __builtin_cpu_supports("avx2") != 0;
}

__attribute__((target("avx2"))) void voxel_codes_avx2(const Grid& grid, std::span<const Vec3f> points,
                                                       std::uint64_t* codes) {
  const __m256d inverse_resolution = _mm256_set1_pd(grid.inverse_resolution());
  const __m256d offset = _mm256_set1_pd(double(grid.key_offset()));
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
    const __m256i code = lanes::codes(x, y, z, inverse_resolution, offset);
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
