// voxel_codes: the Morton code of the finest voxel of many points at once.
//
// The same as morton::encode(*grid.key_checked(p)) point by point, for a
// whole block of a scan: the discrete and fast integrators start every scan
// by finding the end voxel of each of its points (end_voxels.hpp): point by
// point that was 10.5% of the one-thread time of the fast integrator on the
// TUM frames at 2 cm (perf), 6.8% with this. Points without a voxel (a depth
// frame has many invalid pixels) get one of two codes above every Morton
// code instead, so the callers count them without a branch per point.
//
// Two implementations give the same codes bit for bit: a portable one and,
// on x86-64 CPUs with AVX2 (checked at run time, so the library still runs
// on any x86-64), one that does four points per step. voxel_codes picks the
// best the CPU has; the detail functions are there for the test that
// compares them.
#pragma once

#include <cstdint>
#include <span>

#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// The code of a point with a coordinate that is not finite.
inline constexpr std::uint64_t kNonFiniteCode = ~std::uint64_t{0};
/// The code of a finite point outside the map.
inline constexpr std::uint64_t kOutsideCode = ~std::uint64_t{0} - 1;

/// codes[i] = morton::encode(*grid.key_checked(points[i])), or
/// kNonFiniteCode / kOutsideCode when the point has no voxel. `codes` holds
/// points.size() entries.
void voxel_codes(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes);

namespace detail {

/// The portable implementation.
void voxel_codes_scalar(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes);
/// Whether this build and CPU can run voxel_codes_avx2.
bool voxel_codes_avx2_available();
/// The AVX2 implementation (only when voxel_codes_avx2_available()).
void voxel_codes_avx2(const Grid& grid, std::span<const Vec3f> points, std::uint64_t* codes);

}  // namespace detail
}  // namespace umbra
