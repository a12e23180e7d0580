// The projective rule for one brick with AVX2, eight voxels per step (see
// projective_frame.hpp for the rule and its float arithmetic).
//
// Only the functions below are compiled for AVX2 (a target attribute, not a
// flag for the whole file or library), and ProjectiveRule::cleared calls
// them only when the CPU reports AVX2. Every step is the plain code's
// arithmetic on eight lanes (IEEE division and rounding are the same per
// lane, and the build forbids contraction into FMA), and the window's
// readings are gathered with the lanes outside the level masked to 0, so
// the result is the same bit for bit (ProjectiveIntegrator.AvxEqualsPlain).
#include "integrate/projective_frame.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define UMBRA_PROJECTIVE_AVX2 1
#include <immintrin.h>
#endif

namespace umbra::detail {

#if UMBRA_PROJECTIVE_AVX2

bool projective_avx2_available() {
  __builtin_cpu_init();  // may run before the constructors that set up __builtin_cpu_supports
  return __builtin_cpu_supports("avx2") != 0;
}

namespace {

/// cells[(y - first) * stride + (x - first)] where `use` is set, 0
/// elsewhere. The cells read are inside: the callers clamp the projections
/// into the image first (as cleared_plain does, which reads them without a
/// test), so a pixel's column lies in [0, width), a half's in [0, 2 width)
/// and a window's first cell in [-1, cells): testing each lane's bounds
/// again was a sixth of the instructions of a brick.
__attribute__((target("avx2"))) __m256 gather_cells(const float* cells, __m256i x, __m256i y, int first, int stride,
                                                    __m256i use) {
  const __m256i index = _mm256_and_si256(
      _mm256_add_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(y, _mm256_set1_epi32(first)), _mm256_set1_epi32(stride)),
                       _mm256_sub_epi32(x, _mm256_set1_epi32(first))),
      use);
  return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), cells, index, _mm256_castsi256_ps(use), 4);
}

}  // namespace

__attribute__((target("avx2"))) std::uint64_t projective_cleared_avx2(const ProjectiveRule& rule, Vec3f origin,
                                                                     int level) {
  const float* cells = level == 0 ? rule.frame->depth.data() : rule.frame->pyramid.window_max(level);
  const float* halves = rule.frame->depth_halves.empty() ? nullptr : rule.frame->depth_halves.data();
  const int cells_wide = rule.frame->pyramid.width(level);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 limit = _mm256_set1_ps(16777216.0f);
  const __m256 minus_limit = _mm256_set1_ps(-16777216.0f);
  const __m256 base_x = _mm256_set1_ps(origin.x);
  const __m256 base_y = _mm256_set1_ps(origin.y);
  const __m256 base_z = _mm256_set1_ps(origin.z);
  const __m256 fx = _mm256_set1_ps(rule.fx);
  const __m256 fy = _mm256_set1_ps(rule.fy);
  const __m256 cx = _mm256_set1_ps(rule.cx_half);
  const __m256 cy = _mm256_set1_ps(rule.cy_half);
  const __m256 margin = _mm256_set1_ps(rule.margin);
  const __m256 range_squared = _mm256_set1_ps(rule.max_range_squared);
  const bool limited = rule.max_range_squared > 0.0f;
  const __m256 scale = _mm256_set1_ps(DepthPyramid::pixel_cells(level));
  const __m256 half = _mm256_set1_ps(0.5f);
  const __m256 edge_reach = _mm256_set1_ps(rule.edge_reach);
  const __m256 width = _mm256_set1_ps(rule.width);
  const __m256 height = _mm256_set1_ps(rule.height);
  const __m256 width_inside = _mm256_set1_ps(rule.width_inside);
  const __m256 height_inside = _mm256_set1_ps(rule.height_inside);
  std::uint64_t result = 0;
  std::uint64_t seen = 0;
  for (unsigned group = 0; group < 8; ++group) {
    const __m256 x = _mm256_add_ps(base_x, _mm256_loadu_ps(&rule.offset_table[0][8 * group]));
    const __m256 y = _mm256_add_ps(base_y, _mm256_loadu_ps(&rule.offset_table[1][8 * group]));
    const __m256 z = _mm256_add_ps(base_z, _mm256_loadu_ps(&rule.offset_table[2][8 * group]));
    __m256 ok = _mm256_cmp_ps(z, zero, _CMP_GT_OQ);
    if (limited) {
      const __m256 squared = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z));
      ok = _mm256_and_ps(ok, _mm256_cmp_ps(squared, range_squared, _CMP_LE_OQ));
    }
    const __m256 inverse = _mm256_div_ps(_mm256_set1_ps(1.0f), z);
    const __m256 u_free = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(x, inverse), fx), cx);
    const __m256 v_free = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(y, inverse), fy), cy);
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u_free, minus_limit, _CMP_GE_OQ),
                                                       _mm256_cmp_ps(u_free, limit, _CMP_LE_OQ)),
                                         _mm256_and_ps(_mm256_cmp_ps(v_free, minus_limit, _CMP_GE_OQ),
                                                       _mm256_cmp_ps(v_free, limit, _CMP_LE_OQ))));
    // Within the edge reach of the image, clamped into it (as cleared_plain).
    const __m256 reach = _mm256_mul_ps(edge_reach, inverse);
    const __m256 minus_reach = _mm256_sub_ps(zero, reach);
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u_free, minus_reach, _CMP_GE_OQ),
                                                       _mm256_cmp_ps(u_free, _mm256_add_ps(width, reach), _CMP_LT_OQ)),
                                         _mm256_and_ps(_mm256_cmp_ps(v_free, minus_reach, _CMP_GE_OQ),
                                                       _mm256_cmp_ps(v_free, _mm256_add_ps(height, reach), _CMP_LT_OQ))));
    // Lanes not ok may hold anything: clear them before clamping and converting.
    const __m256 u = _mm256_min_ps(_mm256_max_ps(_mm256_and_ps(u_free, ok), zero), width_inside);
    const __m256 v = _mm256_min_ps(_mm256_max_ps(_mm256_and_ps(v_free, ok), zero), height_inside);
    if (_mm256_movemask_ps(ok) == 0) {
      if (rule.seen_depth == 2) return 0;  // a voxel not seen: the brick clears nothing
      continue;
    }
    __m256 d;
    const __m256i use = _mm256_castps_si256(ok);
    if (level == 0 && halves != nullptr) {
      // Its half pixel's reading (the half's nearest, else its pixel's).
      d = gather_cells(halves, _mm256_cvttps_epi32(_mm256_add_ps(u, u)), _mm256_cvttps_epi32(_mm256_add_ps(v, v)), 0,
                       2 * cells_wide, use);
    } else if (level == 0) {
      d = gather_cells(cells, _mm256_cvttps_epi32(u), _mm256_cvttps_epi32(v), 0, cells_wide, use);
    } else {
      const __m256i a = _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_sub_ps(_mm256_mul_ps(u, scale), half)));
      const __m256i b = _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_sub_ps(_mm256_mul_ps(v, scale), half)));
      // The window's first cell (a, b) in [-1, cells) on each axis: one read of window_max.
      d = gather_cells(cells, a, b, -1, cells_wide + 1, use);
    }
    const __m256 cleared = _mm256_and_ps(ok, _mm256_cmp_ps(z, _mm256_sub_ps(d, margin), _CMP_LT_OQ));
    result |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(cleared))) << (8 * group);
    const __m256 seen_lanes = _mm256_and_ps(ok, _mm256_cmp_ps(d, zero, _CMP_GT_OQ));
    seen |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(seen_lanes))) << (8 * group);
  }
  return ProjectiveRule::keep_seen_units(result, seen, rule.seen_depth);
}

#else

bool projective_avx2_available() { return false; }
std::uint64_t projective_cleared_avx2(const ProjectiveRule&, Vec3f, int) { return 0; }

#endif

}  // namespace umbra::detail
