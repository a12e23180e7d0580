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
// The rule here, per finest voxel v of a brick, in float as the rule
// computes it (projective_frame.hpp, "Arithmetic"): camera-frame centre
// (x, y, z) = the brick's origin plus v's offset, 1 / z, u = (x (1 / z))
// fx + (cx + 1/2) and likewise v; h is the half extent of v's cube along
// the camera's z axis (float):
//  - v is *in the band* when the band is on (make() below), z >= z_min
//    (v is at most about 2 kHalfWidthPixels pixels wide there), it is
//    within range (its brick's range node as ProjectiveRule::within_range;
//    with range_depth 0, (x x + y y) + z z <= max_range^2 as the rule), 0 <=
//    u < width and 0 <= v < height, and the readings of the 3 x 3 pixels
//    around its centre's pixel (floor(u), floor(v)) reach its depth: z - h
//    < their largest and z + h + kFrontVoxels resolution >= their least
//    (Readings);
//  - a voxel in the band is cleared exactly when one of the image's rays
//    passes through its cube and ends outside it, the rays cut at
//    max_range: detail::segment_crosses in double, OctoMap's walk visiting
//    the voxel before the ray's end voxel. Every other voxel keeps the
//    rule's answer (the margin applies to it only).
// Far from the surface the two agree, or the difference is free space
// between rays, which the simple integrator leaves unknown (reported, not
// a target). Why the 3 x 3 pixels for the band and not the pixels the cube
// covers: a voxel narrower than the rays' spacing may cover no pixel
// centre; the rule cleared such surface voxels, which the simple
// integrator's rays miss (recall 99.0% instead of 99.85%).
//
// The evaluation (apply_surface_band). Only the rays of the pixels whose
// centres lie within the bounds of the cube's projection (its *footprint*,
// a fiftieth of a pixel wider) can cross it, and only those whose reading
// lies beyond the cube's nearest depth; each is tested in float against
// precomputed reciprocals of its direction (Image::rays), with a margin
// far above float's error, and the few within the margin of an edge of
// the cube or of their end are tested again in double: the answer is the
// double test's. The plain evaluation (apply_surface_band_plain, the
// tests' definition) takes every ray in double. On the simulated camera
// at 2 cm the band still costs about twice the rule's time, and a band up
// to four pixels wide (which the simulated camera at 4 cm needs for 99.5%
// recall on 8 frames) twice TUM's at 2 cm (docs/benchmarks.md).
//
// The walk (projective_tracer.cpp) decides nodes whole: it does not skip a
// node that may hold a band voxel (the rays may clear it where the rule
// does not) nor clear one whole (the rays may keep it): the 3 x 3 pixels'
// readings over the node's centres' pixels (Image::pyramid) bound whether
// any voxel of it is in the band. So the misses are this rule's whatever
// the walk decides whole (the brute-force test evaluates it per brick).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "integrate/depth_pyramid.hpp"
#include "umbra/core/morton.hpp"

namespace umbra {

struct ProjectiveRule;
struct ProjectiveFrame;

struct SurfaceBand {
  /// Voxels up to about 2 x this many pixels wide are in the band (1: those
  /// that read their own pixel, window level 0).
  static constexpr double kHalfWidthPixels = 1.0;
  /// How far in front of the least reading of its 3 x 3 pixels (in voxels) a voxel is in the band.
  static constexpr double kFrontVoxels = 0.5;

  double z_min = 0.0;          ///< voxels in the band lie at least this deep (float: z_min_f)
  double half_depth = 0.0;     ///< h: half the cube's extent along the camera's z axis
  double half_width[2] = {0.0, 0.0};  ///< half the cube's extent along the camera's x and y axes
  double front_depth = 0.0;    ///< h + kFrontVoxels resolutions: the band's reach in front of the readings
  float z_min_f = 0.0f;        ///< the float forms the rule is evaluated with
  float half_depth_f = 0.0f;
  float front_depth_f = 0.0f;
  float half_width_f[2] = {0.0f, 0.0f};
  /// 1 / (z - h) <= footprint_scale / z for every z >= z_min.
  float footprint_scale = 1.0f;

  /// What the band reads of one image, made once a frame; shared, as a rule is copied.
  struct Image {
    /// Per pixel, the least and the largest reading of the 3 x 3 pixels
    /// around it (+infinity and 0 where none has one), and their pyramid:
    /// its least reading is the least there is (the frame's pyramid gives 0
    /// where any pixel has none, which would put every node near a hole in
    /// the band).
    std::vector<float> nearest;
    std::vector<float> farthest;
    DepthPyramid pyramid;
    /// Per pixel, its ray (a depth image has one at most): the reciprocals
    /// of its direction's map-frame components (the end minus the camera,
    /// cut at max_range), in float; and its reading (0: no ray, or one too
    /// near to reach a voxel of the band). A NaN in inverse[0]: a direction
    /// nearly along a face of the voxels, tested in double only.
    struct Ray {
      float inverse[3];
      float depth;
    };
    std::vector<Ray> rays;
    std::vector<float> row_min, row_max;  ///< make()'s scratch: the 3 x 1 minima and maxima
  };
  std::shared_ptr<const Image> image;

  /// The band for `rule`'s frame, or none where it does not apply: images
  /// of scans (their rays are not a depth image's), and resolutions of 5 mm
  /// and finer, where bricks are seen whole and cells decide far nodes (the
  /// TUM frames there agree with the simple integrator to 99.9%).
  /// The frame must have its rays (ProjectiveFrame::set_rays).
  /// With `scratch`: its image is filled in when no band holds it any
  /// more (else a new one is made and kept there), so that consecutive
  /// images reuse its memory (a fresh image's pages were half of make()'s
  /// time on TUM at 2 cm).
  static std::optional<SurfaceBand> make(const ProjectiveRule& rule, std::shared_ptr<Image>* scratch = nullptr);
  /// Whether make() may give a band for a depth image `frame` (its pyramid
  /// built) at this resolution and max_range: else its rays are not needed.
  static bool possible(double resolution, const ProjectiveFrame& frame, double max_range);
};

/// Bounds for the walk, over a node whose voxel centres lie at camera depths
/// [near, far] and project into [u0, u1] x [v0, v1] (padded for the float
/// rule by the caller): whether some voxel of it may be in the band
/// (`may_hold`): then the walk neither skips it (the rays may clear a band
/// voxel the rule keeps) nor clears it whole (they may keep one). False
/// without a band.
struct SurfaceBandBounds {
  bool may_hold = false;
  double nearest = 0.0;   ///< with may_hold: no band voxel's 3 x 3 pixels hold a nearer reading
  double farthest = 0.0;  ///< nor a farther one
};
SurfaceBandBounds surface_band_bounds(const ProjectiveRule& rule, double near, double far, double u0, double u1,
                                      double v0, double v1);

/// The voxels of the brick whose first voxel is `first` that are in the
/// band (bit i: voxel i in Morton order); 0 without a band.
std::uint64_t surface_band_voxels(const ProjectiveRule& rule, Key first);

/// The brick's misses under the band rule: `cleared` (the rule's answer for
/// the brick whose first voxel is `first`, before box and obstacles) with
/// its band voxels decided by the rays. `cleared` unchanged without a band.
std::uint64_t apply_surface_band(const ProjectiveRule& rule, Key first, std::uint64_t cleared);
/// The same by the definition: each band voxel against every ray of the
/// image in double, but those whose reading lies before the cube's nearest
/// depth (they end before it); slow, for the tests.
std::uint64_t apply_surface_band_plain(const ProjectiveRule& rule, Key first, std::uint64_t cleared);

}  // namespace umbra
