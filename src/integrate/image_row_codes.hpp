// image_row_codes: the voxel codes of one row of a depth image, computed
// from the depths without storing the points.
//
// The projective integrator needs only the voxels of a depth image's points
// (their hits), not the points: back-projecting a row into points, storing
// them and computing their codes from memory was 16% of a steady TUM frame
// at 2 cm (about 6 ns a pixel, the back-projection scalar). Here four
// pixels go through back-projection, pose and code in registers (AVX2,
// checked at run time) with back_project_rows' and voxel_codes' arithmetic
// step for step, so the codes are those of the image's points bit for bit
// (a test compares them, and the portable loop below is that definition).
#pragma once

#include <cstdint>

#include "core/voxel_codes.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/depth_image.hpp"

namespace umbra {

/// The code of a pixel without a reading (below kOutsideCode, above every
/// Morton code).
inline constexpr std::uint64_t kNoReadingCode = kOutsideCode - 1;

/// codes[u] = the voxel code (voxel_codes: kNonFiniteCode, kOutsideCode
/// where none) of pixel (u, v)'s point as back_project_rows gives it, for
/// every u of row v; kNoReadingCode for a pixel without a reading.
/// `column_factor[u]` is (u - cx) / fx and `row_factor` (v - cy) / fy, as
/// back_project_rows computes them. `points` is scratch for width() points.
void image_row_codes(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                     const Pose& pose, int v, Vec3f* points, std::uint64_t* codes);

namespace detail {
/// The portable definition (point by point, then voxel_codes).
void image_row_codes_plain(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                           const Pose& pose, int v, Vec3f* points, std::uint64_t* codes);
/// Whether this build and CPU can run image_row_codes_avx2.
bool image_row_codes_avx2_available();
/// Four pixels at a time with AVX2 (only when image_row_codes_avx2_available()).
void image_row_codes_avx2(const Grid& grid, const DepthImage& depth, const double* column_factor, double row_factor,
                          const Pose& pose, int v, std::uint64_t* codes);
}  // namespace detail

}  // namespace umbra
