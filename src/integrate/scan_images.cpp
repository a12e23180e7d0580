#include "integrate/scan_images.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

#include "core/assert.hpp"
#include "tree/group_pool.hpp"  // detail::populate

namespace umbra {

namespace {

/// An image's axes in the map frame: it looks along `normal`; its x runs
/// along `right` and its y along `down` = normal x right (right-handed).
struct FaceAxes {
  Vec3d right;
  Vec3d down;
  Vec3d normal;
  bool cap;
};

/// Side face k looks at azimuth k * 45 degrees, its y along the map's z;
/// faces 8 and 9 look up and down.
FaceAxes face_axes(int face) {
  if (face == ScanImages::kSideFaces) return {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}, true};
  if (face == ScanImages::kSideFaces + 1) return {{1, 0, 0}, {0, 1, 0}, {0, 0, -1}, true};
  const double azimuth = face * (2.0 * std::numbers::pi / ScanImages::kSideFaces);
  const double c = std::cos(azimuth);
  const double s = std::sin(azimuth);
  return {{-s, c, 0}, {0, 0, 1}, {c, s, 0}, false};
}

// Half-extents of the images in units of their focal length (tangents):
// a side face spans 22.5 degrees of azimuth either side of its axis and,
// at its edges, 45 degrees of elevation (tan 45 / cos 22.5); a cap 45
// degrees either side, where it meets the side faces.
const double kSideHalfWidth = std::tan(std::numbers::pi / ScanImages::kSideFaces);
const double kSideHalfHeight = 1.0 / std::cos(std::numbers::pi / ScanImages::kSideFaces);
constexpr double kCapHalfWidth = 1.0;

/// The side face whose axis is nearest to the azimuth of direction (x, y):
/// round(atan2(y, x) / 45 degrees) mod 8, from the octant's comparisons
/// with tan(22.5 degrees) instead of an atan2 (about 1% of a 3DTK scan's
/// insertion). Only a direction within rounding of a border between two
/// faces may get the other one than atan2 would give (the estimate's
/// count of that point then moves to the neighbouring face's edge).
int nearest_side_face(double x, double y) {
  static_assert(ScanImages::kSideFaces == 8);
  const double tan_half = kSideHalfWidth;  // tan(22.5 degrees)
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  if (ay <= tan_half * ax) return x >= 0.0 ? 0 : 4;  // within 22.5 degrees of the x axis
  if (ax <= tan_half * ay) return y >= 0.0 ? 2 : 6;  // of the y axis
  if (x >= 0.0) return y >= 0.0 ? 1 : 7;
  return y >= 0.0 ? 3 : 5;
}

// The coarse cells of estimate_scan_resolution (cells of a cube's face at
// unit focal length).
constexpr double kCoarse = 28.0;  // cells per unit: 1/28 rad = 2 degrees at a face's centre
constexpr int kCoarseSide = 56;

/// The solid angle of coarse cell (i, j) of a cube's face (the same on
/// every face), from a table made once: a pow per filled cell and scan was
/// more than the table.
double coarse_cell_solid_angle(int i, int j) {
  static const std::vector<double> table = [] {
    std::vector<double> t(std::size_t(kCoarseSide) * kCoarseSide);
    for (int b = 0; b < kCoarseSide; ++b) {
      for (int a = 0; a < kCoarseSide; ++a) {
        const double u = (a + 0.5) / kCoarse - 1.0;
        const double v = (b + 0.5) / kCoarse - 1.0;
        t[std::size_t(b) * kCoarseSide + std::size_t(a)] = 1.0 / (kCoarse * kCoarse) / std::pow(1.0 + u * u + v * v, 1.5);
      }
    }
    return t;
  }();
  return table[std::size_t(j) * kCoarseSide + std::size_t(i)];
}

/// `values` set to `count` zeros; where that needs new memory (the first
/// scans of a process) its pages are backed in one call first
/// (detail::populate): the images are the first memory a fresh process
/// writes for a scan, 2,300 pages for a 3DTK scan at about 14 us a page
/// through page faults on the test machine, 10 us populated.
void assign_zeros(std::vector<float>& values, std::size_t count) {
  if (values.capacity() < count) {
    std::vector<float>().swap(values);
    values.reserve(count);
    detail::populate(values.data(), count * sizeof(float));
  }
  values.assign(count, 0.0f);
}

}  // namespace

void ScanImages::build(Vec3f origin, std::span<const Vec3f> points, ScanResolution resolution) {
  const Vec3d o(origin);
  for (std::size_t i = swap_count_; i-- > 0;) {  // each image's own buffers back
    const auto [a, b] = swaps_[i];
    std::swap(faces_[a], faces_[b]);
    std::swap(ray_pixels_[a], ray_pixels_[b]);
    std::swap(ray_points_[a], ray_points_[b]);
  }
  swap_count_ = 0;
  for (int k = 0; k < kFaces; ++k) {
    ProjectiveFrame& face = faces_[static_cast<std::size_t>(k)];
    const FaceAxes axes = face_axes(k);
    // The caps take the coarser resolution on both axes (a LiDAR's rings cross them as circles).
    const double cap_focal = 1.0 / std::max(resolution.horizontal, resolution.vertical);
    face.fx = axes.cap ? cap_focal : 1.0 / resolution.horizontal;
    face.fy = axes.cap ? cap_focal : 1.0 / resolution.vertical;
    const double half_width = axes.cap ? kCapHalfWidth : kSideHalfWidth;
    const double half_height = axes.cap ? kCapHalfWidth : kSideHalfHeight;
    face.width = 2 * static_cast<int>(std::ceil(face.fx * half_width)) + 2 * kOverlap;
    face.height = 2 * static_cast<int>(std::ceil(face.fy * half_height)) + 2 * kOverlap;
    // The pixels are set when the first point falls in (below).
    face.depth.clear();
    face.depth_halves.clear();
    face.cx = 0.5 * face.width - 0.5;
    face.cy = 0.5 * face.height - 0.5;
    face.origin = o;
    face.rotation = {{{axes.right.x, axes.right.y, axes.right.z},
                      {axes.down.x, axes.down.y, axes.down.z},
                      {axes.normal.x, axes.normal.y, axes.normal.z}}};
  }
  // Every point into every image that holds it; each pixel keeps the
  // nearest depth; every image knows its points' rays.
  // A point lies in few of the ten images: its camera-frame depth and then
  // its sideways coordinates are computed one at a time, and the image is
  // left as soon as the point is behind it or beyond its width or height
  // (a pixel's margin over the exact test, which follows with the same
  // coordinates), before the two divisions: projecting every point into
  // every image was a fifth of a 3DTK scan's insertion.
  std::array<double, kFaces> reach_x;  // |x| / z beyond this: outside the image
  std::array<double, kFaces> reach_y;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    const ProjectiveFrame& face = faces_[k];
    reach_x[k] = (0.5 * face.width + 1.0) / face.fx;  // u = fx x / z + width / 2 lies in [0, width)
    reach_y[k] = (0.5 * face.height + 1.0) / face.fy;
    ray_pixels_[k].clear();
    ray_points_[k].clear();
  }
  // A side face sees a point at tan(azimuth off its axis) = |x| / z, so one
  // whose reach stays below tan(60 degrees) never holds a point 67.5
  // degrees or more off its axis: only the point's nearest side face (by
  // its azimuth, nearest_side_face, which may be the neighbour within
  // rounding of a border) and that face's two neighbours can hold it, with
  // the two caps. Trying the other five was half of the binning's
  // instructions. Each image's pixels and rays do not depend on the order
  // in which a point visits the images.
  bool near_sides_only = true;
  for (int k = 0; k < kSideFaces; ++k) near_sides_only = near_sides_only && reach_x[std::size_t(k)] < std::sqrt(3.0);
  for (std::size_t index = 0; index < points.size(); ++index) {
    const Vec3f& p = points[index];
    if (!p.is_finite()) continue;
    const Vec3d d = Vec3d(p) - o;
    std::array<std::uint8_t, kFaces> candidates;
    std::size_t count = 0;
    if (near_sides_only) {
      const auto nearest = static_cast<unsigned>(nearest_side_face(d.x, d.y));
      candidates = {static_cast<std::uint8_t>((nearest + kSideFaces - 1) % kSideFaces), static_cast<std::uint8_t>(nearest),
                    static_cast<std::uint8_t>((nearest + 1) % kSideFaces), kSideFaces, kSideFaces + 1};
      count = 5;
    } else {
      for (std::uint8_t k = 0; k < kFaces; ++k) candidates[k] = k;
      count = kFaces;
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t k = candidates[i];
      ProjectiveFrame& face = faces_[k];
      const auto& r = face.rotation;  // as ProjectiveFrame::rotate computes it
      Vec3d c;
      c.z = r[2][0] * d.x + r[2][1] * d.y + r[2][2] * d.z;
      if (!(c.z > 0.0)) continue;
      c.x = r[0][0] * d.x + r[0][1] * d.y + r[0][2] * d.z;
      if (std::abs(c.x) > reach_x[k] * c.z) continue;
      c.y = r[1][0] * d.x + r[1][1] * d.y + r[1][2] * d.z;
      if (std::abs(c.y) > reach_y[k] * c.z) continue;
      const double u = face.fx * (c.x / c.z) + face.cx + 0.5;
      const double v = face.fy * (c.y / c.z) + face.cy + 0.5;
      if (!(u >= 0.0 && u < face.width && v >= 0.0 && v < face.height)) continue;
      if (face.depth.empty()) {  // its first point
        assign_zeros(face.depth, std::size_t(face.width) * std::size_t(face.height));
        assign_zeros(face.depth_halves, 4 * face.depth.size());
      }
      const std::size_t at =
          std::size_t(static_cast<int>(v)) * std::size_t(face.width) + std::size_t(static_cast<int>(u));
      float& pixel = face.depth[at];
      const auto depth = static_cast<float>(c.z);
      if (pixel == 0.0f || depth < pixel) pixel = depth;
      // Its half pixel: the rule computes it as (int)(u + u) from float u,
      // which may differ from the double here only on a half-pixel border
      // (then the point counts in the neighbouring half: harmless).
      float& half = face.depth_halves[std::size_t(static_cast<int>(2.0 * v)) * std::size_t(2 * face.width) +
                                      std::size_t(static_cast<int>(2.0 * u))];
      if (half == 0.0f || depth < half) half = depth;
      ray_pixels_[k].push_back(static_cast<std::uint32_t>(at));
      ray_points_[k].push_back(static_cast<std::uint32_t>(index));
    }
  }
  // The images that hold a point, to the front, in face order. The others
  // clear nothing (no voxel's window there holds a reading, nor does the
  // edge a voxel outside reads), so they are left out: no pixels, pyramid
  // or walk for the directions the scan did not reach (a 3DTK scan covers
  // about 230 degrees of azimuth: three of its ten images are empty).
  held_ = 0;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    if (faces_[k].depth.empty()) continue;
    if (k != held_) {
      std::swap(faces_[held_], faces_[k]);
      std::swap(ray_pixels_[held_], ray_pixels_[k]);
      std::swap(ray_points_[held_], ray_points_[k]);
      swaps_[swap_count_++] = {static_cast<std::uint8_t>(held_), static_cast<std::uint8_t>(k)};
    }
    ++held_;
  }
  for (std::size_t k = 0; k < held_; ++k) {
    ProjectiveFrame& face = faces_[k];
    // The pyramid's maxima: each pixel's farthest half (by its nearest
    // reading). Then the halves without a point of a pixel with one take
    // the pixel's nearest reading, the one a voxel there reads
    // (projective_frame.hpp): one read a voxel instead of two. Their
    // farthest stays the same (the pixel's nearest is no farther than any
    // of its halves').
    std::vector<float>& farthest = face.farthest_half;
    assign_zeros(farthest, face.depth.size());
    const std::size_t wide = 2 * std::size_t(face.width);
    for (std::size_t y = 0; y < std::size_t(face.height); ++y) {
      for (std::size_t x = 0; x < std::size_t(face.width); ++x) {
        float* top = &face.depth_halves[2 * y * wide + 2 * x];
        float* bottom = top + wide;
        const std::size_t at = y * std::size_t(face.width) + x;
        farthest[at] = std::max(std::max(top[0], top[1]), std::max(bottom[0], bottom[1]));
        const float nearest = face.depth[at];
        top[0] = top[0] == 0.0f ? nearest : top[0];
        top[1] = top[1] == 0.0f ? nearest : top[1];
        bottom[0] = bottom[0] == 0.0f ? nearest : bottom[0];
        bottom[1] = bottom[1] == 0.0f ? nearest : bottom[1];
      }
    }
    face.pyramid.build(face.depth.data(), farthest.data(), face.width, face.height);
    // The image's rays, by pixel (set_rays numbers them in the order given).
    face.set_rays(points, ray_pixels_[k]);
    if (face.ray_order.empty()) {
      face.ray_order.assign(ray_points_[k].begin(), ray_points_[k].end());
    } else {
      for (std::uint32_t& ray : face.ray_order) ray = ray_points_[k][ray];
    }
  }
}

std::size_t ScanImages::memory_bytes() const {
  std::size_t bytes = 0;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    bytes += faces_[k].memory_bytes() + (ray_pixels_[k].capacity() + ray_points_[k].capacity()) * sizeof(std::uint32_t);
  }
  return bytes;
}

namespace detail {

// Sixty-four cells at a time: a row's cells with a filled cell within
// `reach` on the left are the OR of the row shifted right by 1 to `reach`
// cells (and so on for the other side and for the columns, whose
// neighbours are whole rows above and below). One sweep each way per row
// and column, a cell at a time, was a tenth of a 3DTK scan's insertion;
// a search of `reach` cells from every empty cell before that, more.
ScanGaps count_scan_gaps(std::span<const std::uint64_t> filled, int images, int wide, int high, int reach) {
  UMBRA_ASSERT(reach >= 1 && reach < 64);
  const auto words = static_cast<std::size_t>(scan_row_words(wide));
  UMBRA_ASSERT(filled.size() == std::size_t(images) * std::size_t(high) * words);
  ScanGaps gaps;
  // The bits of the row's last word that are cells.
  const std::uint64_t last_word = wide % 64 == 0 ? ~std::uint64_t{0} : (std::uint64_t{1} << (wide % 64)) - 1;
  for (int k = 0; k < images; ++k) {
    const std::uint64_t* image = filled.data() + std::size_t(k) * std::size_t(high) * words;
    const auto row = [&](int j) { return image + std::size_t(j) * words; };
    for (int j = 0; j < high; ++j) {
      const std::uint64_t* cells = row(j);
      for (std::size_t w = 0; w < words; ++w) {
        const std::uint64_t here = cells[w];
        const std::uint64_t before = w > 0 ? cells[w - 1] : 0;  // the lower cells
        const std::uint64_t after = w + 1 < words ? cells[w + 1] : 0;
        std::uint64_t left = 0;   // a filled cell s cells lower (to the left)
        std::uint64_t right = 0;  // s cells higher
        std::uint64_t above = 0;  // s rows up
        std::uint64_t below = 0;
        for (int s = 1; s <= reach; ++s) {
          left |= here << s | before >> (64 - s);
          right |= here >> s | after << (64 - s);
          if (j - s >= 0) above |= row(j - s)[w];
          if (j + s < high) below |= row(j + s)[w];
        }
        const std::uint64_t empty = ~here & (w + 1 == words ? last_word : ~std::uint64_t{0});
        gaps.filled += static_cast<std::size_t>(std::popcount(here));
        gaps.row_gaps += static_cast<std::size_t>(std::popcount(empty & left & right));
        gaps.column_gaps += static_cast<std::size_t>(std::popcount(empty & above & below));
      }
    }
  }
  return gaps;
}

}  // namespace detail

ScanResolution estimate_scan_resolution(Vec3f origin, std::span<const Vec3f> points, ScanResolution given) {
  const Vec3d o(origin);
  // The solid angle the points cover, from cells of about 2 degrees of a
  // cube's faces at unit focal length; and every point in the middle of a
  // side face, as (face, u, v) at unit focal length.
  std::vector<std::uint8_t> coarse(std::size_t(6) * kCoarseSide * kCoarseSide, 0);
  struct OnFace {
    int face;
    float u;
    float v;
  };
  std::vector<OnFace> middle;
  middle.reserve(points.size());
  std::size_t count = 0;
  std::array<FaceAxes, ScanImages::kSideFaces> side_axes;  // once, not a sin and cos per point
  for (int k = 0; k < ScanImages::kSideFaces; ++k) side_axes[static_cast<std::size_t>(k)] = face_axes(k);
  constexpr double kMiddle = 0.5;  // |v| below this: where pixels keep about their nominal height
  for (const Vec3f& p : points) {
    if (!p.is_finite()) continue;
    const Vec3d d = Vec3d(p) - o;
    const double ax = std::abs(d.x);
    const double ay = std::abs(d.y);
    const double az = std::abs(d.z);
    const double largest = std::max({ax, ay, az});
    if (largest == 0.0) continue;
    ++count;
    // The cube face and cell for the covered solid angle.
    const int axis = largest == ax ? 0 : (largest == ay ? 1 : 2);
    const int cube_face = 2 * axis + (d[static_cast<std::size_t>(axis)] < 0.0 ? 1 : 0);
    const double a = d[static_cast<std::size_t>((axis + 1) % 3)] / largest;
    const double b = d[static_cast<std::size_t>((axis + 2) % 3)] / largest;
    const int i = std::clamp(static_cast<int>((a + 1.0) * kCoarse), 0, kCoarseSide - 1);
    const int j = std::clamp(static_cast<int>((b + 1.0) * kCoarse), 0, kCoarseSide - 1);
    coarse[(std::size_t(cube_face) * kCoarseSide + std::size_t(j)) * kCoarseSide + std::size_t(i)] = 1;
    // The side face its azimuth falls in (nearest_side_face: no atan2 a point).
    const int side = nearest_side_face(d.x, d.y);
    const FaceAxes& axes = side_axes[static_cast<std::size_t>(side)];
    const double z = d.dot(axes.normal);
    if (!(z > 0.0)) continue;
    const double v = d.dot(axes.down) / z;
    if (std::abs(v) < kMiddle) middle.push_back({side, static_cast<float>(d.dot(axes.right) / z), static_cast<float>(v)});
  }
  if (count < 16) return given;
  double solid_angle = 0.0;
  for (int k = 0; k < 6; ++k) {
    for (int j = 0; j < kCoarseSide; ++j) {
      for (int i = 0; i < kCoarseSide; ++i) {
        if (!coarse[(std::size_t(k) * kCoarseSide + std::size_t(j)) * kCoarseSide + std::size_t(i)]) continue;
        solid_angle += coarse_cell_solid_angle(i, j);
      }
    }
  }
  const double mean_spacing = std::sqrt(solid_angle / static_cast<double>(count));

  // From a little below the mean spacing, each axis coarsened until few
  // empty pixels lie between filled ones along it.
  ScanResolution result{given.horizontal > 0.0 ? given.horizontal : 0.8 * mean_spacing,
                        given.vertical > 0.0 ? given.vertical : 0.8 * mean_spacing};
  // Only the side faces some middle point falls in are binned and counted:
  // the others have no filled cell and so no gap (a 3DTK scan leaves three
  // of the eight empty).
  std::array<int, ScanImages::kSideFaces> slot;  // a face's image in `filled`
  slot.fill(-1);
  for (const OnFace& q : middle) slot[static_cast<std::size_t>(q.face)] = 0;
  int used = 0;
  for (int& s : slot) {
    if (s == 0) s = used++;
  }
  std::vector<std::uint64_t> filled;  // bit rows (count_scan_gaps)
  constexpr int kReach = 4;  // a gap is at most this many pixels from a filled one on either side
  for (int round = 0; round < 16; ++round) {
    const int wide = 2 * static_cast<int>(std::ceil(kSideHalfWidth / result.horizontal));
    const int high = 2 * static_cast<int>(std::ceil(kMiddle / result.vertical));
    const auto words = static_cast<std::size_t>(detail::scan_row_words(wide));
    filled.assign(std::size_t(used) * std::size_t(high) * words, 0);
    for (const OnFace& q : middle) {
      const int i = std::clamp(static_cast<int>((q.u / kSideHalfWidth + 1.0) * 0.5 * wide), 0, wide - 1);
      const int j = std::clamp(static_cast<int>((q.v / kMiddle + 1.0) * 0.5 * high), 0, high - 1);
      const auto image = std::size_t(slot[static_cast<std::size_t>(q.face)]);
      filled[(image * std::size_t(high) + std::size_t(j)) * words + std::size_t(i) / 64] |= std::uint64_t{1} << (i % 64);
    }
    const detail::ScanGaps gaps = detail::count_scan_gaps(filled, used, wide, high, kReach);
    const std::size_t cells = gaps.filled;
    const std::size_t row_gaps = gaps.row_gaps;
    const std::size_t column_gaps = gaps.column_gaps;
    const bool coarser_rows = given.horizontal <= 0.0 && row_gaps * 50 > cells;
    const bool coarser_columns = given.vertical <= 0.0 && column_gaps * 50 > cells;
    if (!coarser_rows && !coarser_columns) break;
    if (coarser_rows) result.horizontal *= 1.2;
    if (coarser_columns) result.vertical *= 1.2;
  }
  return result;
}

}  // namespace umbra
