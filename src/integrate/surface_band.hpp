// The surface band: where the projective rule decides a voxel as the simple
// integrator does, by the rays themselves.
//
// Why. The rule (projective_frame.hpp) reads a voxel's own pixel where the
// voxel is narrower than two pixels. A camera with wide pixels (the
// simulated one: fx 204, a 2 cm voxel is one pixel wide at 4 m) then gives
// a surface voxel the verdict of one noisy reading, where one to four rays
// cross it in the simple integrator (OctoMap's insertPointCloud): a surface
// voxel got one miss more or less than there about 1% of the time, and
// occupied recall and precision against the simple integrator were 99.14%
// and 98.33% on the whole sequence at 2 cm (issue 22: >= 99.5% and 99%).
// A 2 x 2 window of pixels, or a surface margin, traded one for the other.
//
// The rule here, per finest voxel v with camera-frame centre c = (x, y, z)
// (double), projected to (u, v) as the rule projects it, h the half extent
// of v's cube along the camera's z axis, rho = sqrt(3)/2 resolution its
// half diagonal:
//  - v is *eligible* when the band is on (make() below), z >= z_min (v is
//    at most about two pixels wide there: 2 kHalfWidthPixels), its centre
//    projects inside the image, and it is within range (its brick's range
//    node as ProjectiveRule::within_range; with range_depth 0 its centre
//    within max_range);
//  - v is *in the band* when eligible and the readings (> 0) of the 3 x 3
//    pixels around its centre's pixel reach its depth: z - h < max(d) and
//    z + h + kFrontVoxels resolution >= min(d);
//  - its *footprint* P: the pixels whose centres (where their rays pass)
//    lie within e_u = fx (w_x + |x| / z h) / (z - h) of u and e_v
//    (likewise) of v, w_x being half the cube's extent along the camera's x
//    axis: a bound of the cube's projection, a hundredth of a pixel wider,
//    so every ray that meets the cube is a ray of P;
//  - a voxel in the band is cleared exactly when one of the rays of P passes
//    through its cube and ends outside it (after max_range truncation), the
//    segment-cube test of ProjectiveRule::ray_crosses: OctoMap's walk visits
//    it before the ray's end voxel. Every other voxel keeps the rule's
//    answer (the margin applies to it only).
// Far from the surface the two agree, or the difference is free space
// between rays, which the simple integrator leaves unknown (reported, not
// a target). Why the 3 x 3 pixels and not P for the band: a voxel
// narrower than the rays' spacing may hold no pixel centre (P empty); the
// rule cleared such surface voxels, which the simple integrator's rays
// miss (recall 99.0% instead of 99.85% with P alone). kFrontVoxels: 2
// voxels gave 99.85% / 99.85%, 0.5 99.83% / 99.85% with fewer band voxels.
//
// The walk (projective_tracer.cpp) decides nodes whole: it splits a node
// that may hold a band voxel the rays clear (instead of skipping it) or any
// band voxel at all (instead of clearing it whole), from frame-wide bounds:
// P and the 3 x 3 pixels lie within R = fx rho (1 + max(|x|, |y|) / z) /
// (z - rho) + 1 pixels of (u, v) (reach_u; fy likewise), R largest at
// z_min and the image's edges. So the misses are this rule's whatever the
// walk decides whole (the brute-force test evaluates it per brick).
//
// Cost: the sixteen simulated frames at 2 cm take about 4 times the CPU
// time they took before (docs/benchmarks.md), the bricks beyond z_min being
// evaluated voxel by voxel in double; TUM at 2 cm has few voxels beyond
// z_min (5.25 m), and 5 mm and finer have no band.
#pragma once

#include <cstdint>
#include <optional>

#include <memory>
#include <vector>

#include "umbra/core/morton.hpp"
#include "integrate/depth_pyramid.hpp"

namespace umbra {

struct ProjectiveRule;
struct ProjectiveFrame;

struct SurfaceBand {
  double z_min = 0.0;          ///< eligible voxels lie at least this deep
  double half_depth = 0.0;     ///< h: half the cube's extent along the camera's z axis
  double half_width[2] = {0.0, 0.0};  ///< half the cube's extent along the camera's x and y axes
  double front_depth = 0.0;    ///< h + kFrontVoxels resolutions: the band's reach in front of the readings
  double half_diagonal = 0.0;  ///< rho
  /// The largest R of an eligible voxel (centre in the image, z >= z_min):
  /// the footprint of a node's band voxels lies within its centres'
  /// pixels widened by this much.
  double reach_u = 0.0;
  double reach_v = 0.0;

  /// Voxels up to about 2 x this many pixels wide are eligible (1: those
  /// that read their own pixel, window level 0).
  static constexpr double kHalfWidthPixels = 1.0;
  /// Per pixel, the least and the largest reading of the 3 x 3 pixels
  /// around it (+infinity and 0 where none has one), and their pyramid:
  /// its least reading is the least there is (the frame's pyramid gives 0
  /// where any pixel has none, which would put every node near a hole in
  /// the band). Shared: a rule is copied.
  struct Readings {
    std::vector<float> nearest;
    std::vector<float> farthest;
    DepthPyramid pyramid;
  };
  std::shared_ptr<const Readings> readings;

  /// How far in front of the nearest reading of its footprint (in voxels) a voxel is in the band.
  static constexpr double kFrontVoxels = 0.5;

  /// The band for `rule`'s frame, or none where it does not apply: images
  /// of scans (their rays are not a depth image's), and resolutions of 5 mm
  /// and finer, where bricks are seen whole and cells decide far nodes (the
  /// TUM frames there agree with the simple integrator to 99.9%).
  /// The frame must have its rays (ProjectiveFrame::set_rays).
  static std::optional<SurfaceBand> make(const ProjectiveRule& rule);
  /// Whether make() may give a band for a depth image `frame` (its pyramid
  /// built) at this resolution and max_range: else its rays are not needed.
  static bool possible(double resolution, const ProjectiveFrame& frame, double max_range);
};

/// Bounds for the walk, over a node whose voxel centres lie at camera depths
/// [near, far] and project into [u0, u1] x [v0, v1] (padded for rounding
/// by the caller): whether some voxel of it may be in the band and cleared
/// by a ray (`may_clear`), and whether some may be in the band at all
/// (`may_hold`). Both false without a band.
struct SurfaceBandBounds {
  bool may_clear = false;
  bool may_hold = false;
  double nearest = 0.0;  ///< with may_hold: no band voxel's footprint holds a nearer reading
  double farthest = 0.0;  ///< nor a farther one
};
SurfaceBandBounds surface_band_bounds(const ProjectiveRule& rule, double near, double far, double u0, double u1,
                                      double v0, double v1);

/// The brick's misses under the band rule: `cleared` (the rule's answer for
/// the brick whose first voxel is `first`, before box and obstacles) with
/// its band voxels decided by the rays. `cleared` unchanged without a band.
std::uint64_t apply_surface_band(const ProjectiveRule& rule, Key first, std::uint64_t cleared);

}  // namespace umbra
