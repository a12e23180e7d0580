// ScanImages: a scan from one origin (a LiDAR scan) as ten depth images
// around its origin, for the projective integrator.
//
// A rotating LiDAR has no image, but its points, seen from its origin, are
// one. Ten pinhole images cover every direction: eight side faces around
// the map's vertical axis (45 degrees of azimuth each, their rows
// horizontal, up to about 48 degrees of elevation) and two caps (90 by 90
// degrees, up and down), each reaching a few pixels past its share so that
// the windows of voxels near a seam find readings on both sides. Every
// point is drawn into every image that holds it; a pixel keeps the nearest
// point's depth along the image's axis; images no point falls in are
// left out (they would clear nothing). The images are ProjectiveFrames:
// the integrator clears a voxel when the rule (projective_frame.hpp) clears
// it on some image. Eight side faces rather than four: a pinhole pixel's
// angular width shrinks by cos^2 of its angle from the image's axis, to
// half at 45 degrees, and a LiDAR's beams then leave holes between them
// near a quarter-turn face's edges; at 22.5 degrees it shrinks by 15%.
//
// The pixels' angular size at a side face's centre is the scan's angular
// resolution, horizontal and vertical (a rotating LiDAR's rings run along
// the rows and are often several times farther apart than its steps along a
// ring); the caps take the coarser of the two on both axes. It is given
// (InsertOptions::scan_resolution) or estimated per scan by
// estimate_scan_resolution. A pixel holding no point is a pixel without a
// reading: too fine an image punches holes between the scan's lines (whose
// voxels then stay unknown), too coarse a one keeps only the nearest of
// several points (the space in front of the others stays unknown where it
// is behind the nearest).
//
// What a range image cannot represent: points behind points in one pixel
// (the farther ones clear nothing beyond the nearest; a scan of a fence or
// foliage keeps less free space than the simple integrator would), and
// points from several origins (a scan must come from one origin: a moving
// sensor's deskewed sweep is integrated as if it did, so free space near
// the sensor's path is approximate; use the simple or fast integrator for
// those). Known obstacles are cleared only where a ray crosses them
// (projective_frame.hpp), so neither clears an obstacle no ray crossed.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "umbra/core/vec3.hpp"
#include "umbra/integrate/insert_options.hpp"
#include "integrate/projective_frame.hpp"

namespace umbra {

class ScanImages {
 public:
  static constexpr int kSideFaces = 8;
  static constexpr int kFaces = kSideFaces + 2;
  /// Pixels each image reaches past its share on every side.
  static constexpr int kOverlap = 8;

  /// The images of the scan (points and origin in the map frame; non-finite
  /// points are skipped); both resolutions > 0. The images' rays are
  /// `points`, which must outlive the images' use.
  void build(Vec3f origin, std::span<const Vec3f> points, ScanResolution resolution);

  /// The images that hold at least one point (in face order; the others
  /// would clear nothing): none for a scan without points.
  [[nodiscard]] std::span<const ProjectiveFrame> faces() const { return {faces_.data(), held_}; }
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  std::array<ProjectiveFrame, kFaces> faces_;  ///< the first held_ hold points
  std::size_t held_ = 0;
  // The swaps that moved the held images to the front, undone before the
  // next scan so that each image gets its own buffers back (a cap's are
  // four times a side image's).
  std::array<std::pair<std::uint8_t, std::uint8_t>, kFaces> swaps_{};
  std::size_t swap_count_ = 0;
  // Each image's rays (pixel, point) as the points are drawn in; kept
  // between scans so that their buffers are reused.
  std::array<std::vector<std::uint32_t>, kFaces> ray_pixels_;
  std::array<std::vector<std::uint32_t>, kFaces> ray_points_;
};

/// The angular resolution of a scan's images (radians), where `given` has 0:
/// from 0.8 times the scan's mean angular spacing (the covered solid angle
/// over the point count), each axis coarsened by 20% at a time while more
/// than 2% of the empty pixels in the middle of the side faces lie between
/// two filled ones at most four pixels away along it. `given` as it is when
/// the scan has fewer than 16 finite points that are not at the origin.
ScanResolution estimate_scan_resolution(Vec3f origin, std::span<const Vec3f> points, ScanResolution given);

namespace detail {
struct ScanGaps {
  std::size_t filled = 0;
  std::size_t row_gaps = 0;
  std::size_t column_gaps = 0;
};
/// The 64-bit words of one row of `wide` cells.
constexpr int scan_row_words(int wide) { return (wide + 63) / 64; }
/// Over `images` images of `wide` x `high` cells held as bit rows (row j
/// of image k is the scan_row_words(wide) words from (k * high + j) *
/// scan_row_words(wide); cell i is bit i % 64 of word i / 64, set where a
/// point fell, bits past `wide` clear): the filled cells, and the empty
/// cells with a filled cell at most `reach` (1 to 63) cells away on both
/// sides along their row (row_gaps) and along their column (column_gaps).
/// estimate_scan_resolution's test of too fine an image.
ScanGaps count_scan_gaps(std::span<const std::uint64_t> filled, int images, int wide, int high, int reach);
}  // namespace detail

}  // namespace umbra
