// A depth image row's candidate voxels: the codes of its pixels (from
// image_row_codes) less those repeated from the pixel to the left or from
// the last pixel with a reading above (ImagePoints::find_voxels_streamed).
//
// Neighbouring pixels mostly share a voxel: a TUM frame at 2 cm keeps about
// 70,000 of its 307,200 pixels' codes. The scalar loop (branch-free) cost
// about 28 instructions a pixel, 8.6 M a frame, 9% of a frame's insertion
// (callgrind); four pixels at a time in AVX2 registers it is about a fifth
// of that. Both keep the same codes in the same order.
#pragma once

#include <cstddef>
#include <cstdint>

namespace umbra {

/// What keep_row_candidates passed over besides the repeats.
struct RowCandidateCounts {
  std::size_t non_finite = 0;  // pixels whose point is not finite (kNonFiniteCode)
  std::size_t outside = 0;     // pixels whose point lies outside the map (kOutsideCode)
};

/// Compacts codes[0, columns) in place to the row's candidates and returns
/// how many: each code of a voxel (not kNonFiniteCode, kOutsideCode or
/// kNoReadingCode) that equals neither the code to its left nor above[u],
/// in column order. above[u] becomes codes[u] where the pixel has a
/// reading (code != kNoReadingCode). Counts the pixels without a voxel.
std::size_t keep_row_candidates(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                 RowCandidateCounts& counts);

namespace detail {
std::size_t keep_row_candidates_plain(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                      RowCandidateCounts& counts);
/// Only where voxel_codes_avx2_available().
std::size_t keep_row_candidates_avx2(std::uint64_t* codes, std::uint64_t* above, std::size_t columns,
                                     RowCandidateCounts& counts);
}  // namespace detail

}  // namespace umbra
