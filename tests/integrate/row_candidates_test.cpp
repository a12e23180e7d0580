// A row's candidate voxels (row_candidates.hpp): the AVX2 loop keeps the
// same codes in the same order as the scalar rule, leaves the same codes
// above and counts the same pixels without a voxel, on rows of any width
// (tails of 0 to 3 pixels) with repeats, markers and pixels without a reading.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/voxel_code_lanes.hpp"
#include "core/voxel_codes.hpp"
#include "integrate/image_row_codes.hpp"
#include "integrate/row_candidates.hpp"

namespace umbra {
namespace {

/// The rule written out plainly, for reference: kept codes, above updated.
std::vector<std::uint64_t> reference(const std::vector<std::uint64_t>& row, std::vector<std::uint64_t>& above,
                                     RowCandidateCounts& counts) {
  std::vector<std::uint64_t> kept;
  std::uint64_t left = kNoReadingCode;
  for (std::size_t u = 0; u < row.size(); ++u) {
    const std::uint64_t code = row[u];
    if (code == kNonFiniteCode) ++counts.non_finite;
    if (code == kOutsideCode) ++counts.outside;
    const bool voxel = code != kNonFiniteCode && code != kOutsideCode && code != kNoReadingCode;
    if (voxel && code != left && code != above[u]) kept.push_back(code);
    left = code;
    if (code != kNoReadingCode) above[u] = code;
  }
  return kept;
}

TEST(RowCandidates, PlainAndAvx2KeepTheRulesCodes) {
  std::mt19937_64 rng(22);
  const bool avx2 = detail::voxel_codes_avx2_available();
  if (!avx2) GTEST_LOG_(INFO) << "no AVX2 here: only the scalar loop is checked";
  for (std::size_t width : {1u, 2u, 3u, 4u, 5u, 7u, 8u, 13u, 64u, 640u}) {
    std::vector<std::uint64_t> above_ref(width, kNonFiniteCode);
    std::vector<std::uint64_t> above_plain = above_ref;
    std::vector<std::uint64_t> above_avx2 = above_ref;
    for (int row_index = 0; row_index < 40; ++row_index) {
      // Runs of equal codes (a voxel across pixels), a few distinct codes
      // so that the row above repeats them, the three markers, large codes.
      std::vector<std::uint64_t> row(width);
      std::uint64_t code = rng() % 6;
      for (std::size_t u = 0; u < width; ++u) {
        const std::uint64_t pick = rng() % 16;
        if (pick < 6) {
          code = rng() % 6;
        } else if (pick == 6) {
          code = kNoReadingCode;
        } else if (pick == 7) {
          code = kNonFiniteCode;
        } else if (pick == 8) {
          code = kOutsideCode;
        } else if (pick == 9) {
          code = (std::uint64_t{1} << 63) - 1 - rng() % 3;  // the largest codes of 21 depth levels
        }
        row[u] = code;
      }
      RowCandidateCounts ref_counts;
      const std::vector<std::uint64_t> expected = reference(row, above_ref, ref_counts);
      for (const bool vector : {false, true}) {
        if (vector && !avx2) continue;
        std::vector<std::uint64_t> codes = row;
        std::vector<std::uint64_t>& above = vector ? above_avx2 : above_plain;
        RowCandidateCounts counts;
        const std::size_t n = vector ? detail::keep_row_candidates_avx2(codes.data(), above.data(), width, counts)
                                     : detail::keep_row_candidates_plain(codes.data(), above.data(), width, counts);
        ASSERT_EQ(std::vector<std::uint64_t>(codes.begin(), codes.begin() + static_cast<std::ptrdiff_t>(n)), expected)
            << (vector ? "avx2" : "plain") << " width " << width << " row " << row_index;
        ASSERT_EQ(above, above_ref) << (vector ? "avx2" : "plain");
        EXPECT_EQ(counts.non_finite, ref_counts.non_finite);
        EXPECT_EQ(counts.outside, ref_counts.outside);
      }
    }
  }
}

}  // namespace
}  // namespace umbra
