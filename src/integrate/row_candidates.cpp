#include "integrate/row_candidates.hpp"

#include <array>
#include <bit>

#include "core/voxel_code_lanes.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/image_row_codes.hpp"

namespace umbra {

std::size_t keep_row_candidates(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                RowCandidateCounts& counts) {
  static const bool avx2 = detail::voxel_codes_avx2_available();  // the CPU does not change
  return avx2 ? detail::keep_row_candidates_avx2(codes, above, columns, counts)
              : detail::keep_row_candidates_plain(codes, above, columns, counts);
}

namespace detail {

namespace {

/// The scalar rule from column `u` on, the code to the left of u being
/// `left`, `n` codes kept before u (n <= u: kept codes are written at or
/// before the pixel they came from, so the row is compacted in place).
std::size_t keep_from(std::uint64_t* codes, std::uint64_t* above, std::size_t u, std::size_t columns, std::uint64_t left,
                      std::size_t n, RowCandidateCounts& counts) {
  // Without branches: whether a pixel's code is kept is unpredictable
  // (voxel borders, pixels without readings). `left` is kNoReadingCode
  // at the row's start and after a pixel without a reading: never equal to a
  // reading's code.
  for (; u < columns; ++u) {
    const std::uint64_t code = codes[u];
    const bool reading = code != kNoReadingCode;
    const bool repeat = (code == left) | (code == above[u]);
    codes[n] = code;
    n += static_cast<std::size_t>((code < kNoReadingCode) & !repeat);
    counts.non_finite += static_cast<std::size_t>(code == kNonFiniteCode);
    counts.outside += static_cast<std::size_t>(code == kOutsideCode);
    left = code;
    above[u] = reading ? code : above[u];
  }
  return n;
}

}  // namespace

std::size_t keep_row_candidates_plain(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                      RowCandidateCounts& counts) {
  return keep_from(codes, above, 0, columns, kNoReadingCode, 0, counts);
}

#if UMBRA_VOXEL_CODE_LANES

namespace {

/// For each 4-bit mask of kept lanes, the 32-bit lane indices that move
/// the kept 64-bit lanes to the front, in order (_mm256_permutevar8x32_epi32).
constexpr std::array<std::array<int, 8>, 16> compaction_table() {
  std::array<std::array<int, 8>, 16> table{};
  for (unsigned mask = 0; mask < 16; ++mask) {
    int out = 0;
    for (int lane = 0; lane < 4; ++lane) {
      if ((mask >> lane & 1u) != 0) {
        table[mask][2 * out] = 2 * lane;
        table[mask][2 * out + 1] = 2 * lane + 1;
        ++out;
      }
    }
    for (; out < 4; ++out) {  // unused lanes: anything
      table[mask][2 * out] = 0;
      table[mask][2 * out + 1] = 1;
    }
  }
  return table;
}

constexpr std::array<std::array<int, 8>, 16> kCompaction = compaction_table();

}  // namespace

__attribute__((target("avx2"))) std::size_t keep_row_candidates_avx2(std::uint64_t* codes, std::uint64_t* above,
                                                                      std::size_t columns,
                                                                      RowCandidateCounts& counts) {
  static_assert(kNoReadingCode >= (std::uint64_t{1} << 63) && kOutsideCode >= (std::uint64_t{1} << 63),
                "a voxel's code (63 bits at most) is >= 0 as a signed lane, the markers are not");
  const __m256i no_reading = _mm256_set1_epi64x(static_cast<long long>(kNoReadingCode));
  const __m256i non_finite = _mm256_set1_epi64x(static_cast<long long>(kNonFiniteCode));
  const __m256i outside = _mm256_set1_epi64x(static_cast<long long>(kOutsideCode));
  const __m256i minus_one = _mm256_set1_epi64x(-1);
  __m256i previous = no_reading;  // the last four codes: lane 3 is left of the next lane 0
  __m256i non_finite_lanes = _mm256_setzero_si256();  // each lane counts down (compares give -1)
  __m256i outside_lanes = _mm256_setzero_si256();
  std::size_t n = 0;
  std::size_t u = 0;
  for (; u + 4 <= columns; u += 4) {
    const __m256i code = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(codes + u));
    const __m256i up = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(above + u));
    // [previous 3, code 0, code 1, code 2]
    const __m256i rotated = _mm256_permute4x64_epi64(code, _MM_SHUFFLE(2, 1, 0, 3));
    const __m256i left = _mm256_blend_epi32(rotated, _mm256_permute4x64_epi64(previous, _MM_SHUFFLE(3, 3, 3, 3)), 0x03);
    const __m256i repeat = _mm256_or_si256(_mm256_cmpeq_epi64(code, left), _mm256_cmpeq_epi64(code, up));
    const __m256i voxel = _mm256_cmpgt_epi64(code, minus_one);  // not one of the markers
    const auto kept = static_cast<unsigned>(_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_andnot_si256(repeat, voxel))));
    const __m256i order = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kCompaction[kept].data()));
    // Writes codes[n, n + 4) with n <= u: only lanes already loaded.
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(codes + n), _mm256_permutevar8x32_epi32(code, order));
    n += static_cast<std::size_t>(std::popcount(kept));
    non_finite_lanes = _mm256_add_epi64(non_finite_lanes, _mm256_cmpeq_epi64(code, non_finite));
    outside_lanes = _mm256_add_epi64(outside_lanes, _mm256_cmpeq_epi64(code, outside));
    const __m256i without_reading = _mm256_cmpeq_epi64(code, no_reading);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(above + u), _mm256_blendv_epi8(code, up, without_reading));
    previous = code;
  }
  alignas(32) std::array<std::int64_t, 4> lanes;
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes.data()), non_finite_lanes);
  counts.non_finite += static_cast<std::size_t>(-(lanes[0] + lanes[1] + lanes[2] + lanes[3]));
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes.data()), outside_lanes);
  counts.outside += static_cast<std::size_t>(-(lanes[0] + lanes[1] + lanes[2] + lanes[3]));
  const auto left = static_cast<std::uint64_t>(_mm256_extract_epi64(previous, 3));
  return keep_from(codes, above, u, columns, left, n, counts);
}

#else

std::size_t keep_row_candidates_avx2(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                     RowCandidateCounts& counts) {
  return keep_row_candidates_plain(codes, above, columns, counts);
}

#endif

}  // namespace detail
}  // namespace umbra
