#include "integrate/surface_band.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "core/assert.hpp"
#include "integrate/projective_frame.hpp"

namespace umbra {

namespace {

/// The pixel rectangle [u0, u1] x [v0, v1] (floors of the bounds) clipped
/// to the image; none when it misses the image.
struct PixelRect {
  int u0, v0, u1, v1;
};
std::optional<PixelRect> clip(const ProjectiveFrame& frame, double u_lo, double u_hi, double v_lo, double v_hi) {
  const double u0 = std::max(std::floor(u_lo), 0.0);
  const double v0 = std::max(std::floor(v_lo), 0.0);
  const double u1 = std::min(std::floor(u_hi), frame.width - 1.0);
  const double v1 = std::min(std::floor(v_hi), frame.height - 1.0);
  if (!(u0 <= u1 && v0 <= v1)) return std::nullopt;
  return PixelRect{static_cast<int>(u0), static_cast<int>(v0), static_cast<int>(u1), static_cast<int>(v1)};
}

/// Slack for depth bounds in double against the float rule (its centres
/// differ from the exact ones by kProjectiveRelativeError of their size).
double depth_slack(double far) { return 1e-5 * (1.0 + std::abs(far)); }

/// A ray whose direction has a component below this share of its length
/// runs nearly along a face of the voxels: tested in double only (see
/// crosses_in_float).
constexpr double kLeastComponent = 1e-4;

/// The float crossing test's margin, in units of the ray's length (0 at
/// the camera, 1 at its end; see crosses_in_float).
constexpr float kCrossingMargin = 1e-5f;

enum class Crossing { no, yes, unsure };

/// detail::segment_crosses for the cube [lo, hi) (`lo`, `hi`: its corners
/// minus the camera's position, each rounded from double) and a ray with
/// direction reciprocals `inverse` (Image::Ray), in float: the slab test
/// with the ray's parameters clamped to [-1, 2] (which keeps every
/// comparison below). Each parameter is the double test's (lo - o) / d
/// within 4 float roundings (relative 2.4e-7; clamped, 6e-7 absolute), so
/// an answer by a margin of 1e-5 is the double test's: enter < exit (the
/// ray meets the cube) and exit < 1 (it leaves before its end, so it does
/// not end inside: the double test's separate check of the end agrees, as
/// each component of the direction is at least kLeastComponent of it).
/// Unsure within the margin.
Crossing crosses_in_float(const float lo[3], const float hi[3], const float inverse[3]) {
  float enter = 0.0f;
  float exit = 2.0f;
  for (std::size_t a = 0; a < 3; ++a) {
    const float t0 = std::min(std::max(lo[a] * inverse[a], -1.0f), 2.0f);
    const float t1 = std::min(std::max(hi[a] * inverse[a], -1.0f), 2.0f);
    enter = std::max(enter, std::min(t0, t1));
    exit = std::min(exit, std::max(t0, t1));
  }
  if (enter + kCrossingMargin < exit && exit + kCrossingMargin < 1.0f) return Crossing::yes;
  if (enter > exit + kCrossingMargin || exit > 1.0f + kCrossingMargin) return Crossing::no;
  return Crossing::unsure;
}

/// A voxel of the band: its index in the brick, its float centre, 1 / z
/// and its projection.
struct BandVoxel {
  unsigned index;
  float x, y, z, inverse, u, v;
};

/// The brick's voxels in the band (the header's definition), with their
/// centres; how many.
int band_voxels(const ProjectiveRule& rule, Key first, std::array<BandVoxel, 64>& out) {
  const SurfaceBand& band = *rule.surface_band;
  const ProjectiveFrame& frame = *rule.frame;
  // Bounds of the brick's float centres and projections first (float
  // rounding is monotonic: a voxel's x = base.x + offset lies between the
  // sums with the least and the largest offset, likewise 1 / z, x (1 / z)
  // and u): none deep enough, or no reading of their 3 x 3 pixels near
  // them, and none is in the band.
  const Vec3f base = rule.brick_origin(first);
  const float z_hi = base.z + rule.offset_max[2];
  if (!(z_hi >= band.z_min_f)) return 0;
  if (!rule.within_range(first)) return 0;  // no voxel in range (the rule clears none there either)
  const float z_lo = std::max(base.z + rule.offset_min[2], band.z_min_f);  // of the voxels deep enough
  const float x_lo = base.x + rule.offset_min[0];
  const float x_hi = base.x + rule.offset_max[0];
  const float y_lo = base.y + rule.offset_min[1];
  const float y_hi = base.y + rule.offset_max[1];
  const float near_inverse = 1.0f / z_lo;
  const float far_inverse = 1.0f / z_hi;
  const float u_lo = std::min(x_lo * near_inverse, x_lo * far_inverse) * rule.fx + rule.cx_half;
  const float u_hi = std::max(x_hi * near_inverse, x_hi * far_inverse) * rule.fx + rule.cx_half;
  const float v_lo = std::min(y_lo * near_inverse, y_lo * far_inverse) * rule.fy + rule.cy_half;
  const float v_hi = std::max(y_hi * near_inverse, y_hi * far_inverse) * rule.fy + rule.cy_half;
  if (!(u_hi >= 0.0f && u_lo < rule.width && v_hi >= 0.0f && v_lo < rule.height)) return 0;
  const DepthPyramid::Range readings = band.image->pyramid.range(
      static_cast<int>(std::max(u_lo, 0.0f)), static_cast<int>(std::max(v_lo, 0.0f)),
      static_cast<int>(std::min(u_hi, rule.width - 1.0f)), static_cast<int>(std::min(v_hi, rule.height - 1.0f)));
  if (!(z_lo - band.half_depth_f < readings.max && z_hi + band.front_depth_f >= readings.min)) return 0;
  const float* nearest = band.image->nearest.data();
  const float* farthest = band.image->farthest.data();
  const std::size_t stride = static_cast<std::size_t>(frame.width);
  int count = 0;
  for (unsigned i = 0; i < 64; ++i) {
    const float z = base.z + rule.offset_table[2][i];
    if (!(z >= band.z_min_f)) continue;
    // The brick's readings, sooner than the voxel's own.
    if (z + band.front_depth_f < readings.min || !(z - band.half_depth_f < readings.max)) continue;
    const float x = base.x + rule.offset_table[0][i];
    const float y = base.y + rule.offset_table[1][i];
    if (rule.max_range_squared > 0.0f && !((x * x + y * y) + z * z <= rule.max_range_squared)) continue;
    const float inverse = 1.0f / z;
    const float u = (x * inverse) * rule.fx + rule.cx_half;
    const float v = (y * inverse) * rule.fy + rule.cy_half;
    if (!(u >= 0.0f && u < rule.width && v >= 0.0f && v < rule.height)) continue;
    const std::size_t own = static_cast<std::size_t>(v) * stride + static_cast<std::size_t>(u);
    if (!(z - band.half_depth_f < farthest[own] && z + band.front_depth_f >= nearest[own])) continue;
    out[static_cast<std::size_t>(count++)] = BandVoxel{i, x, y, z, inverse, u, v};
  }
  return count;
}

/// ceil(a) where a >= 0, else 0.
int ceil_at_least_zero(float a) {
  if (!(a > 0.0f)) return 0;
  const int whole = static_cast<int>(a);
  return static_cast<float>(whole) < a ? whole + 1 : whole;
}
/// floor(a) where a >= 0, else -1 (an empty range from 0).
int floor_or_minus_one(float a) { return a >= 0.0f ? static_cast<int>(a) : -1; }

/// The cube of voxel `first` + Morton offset `index`, in double.
struct Cube {
  Vec3d lo, hi;
};
Cube cube_of(const Grid& grid, Key first, unsigned index) {
  const Key offset = morton::decode(index);
  const double res = grid.resolution();
  const Vec3d lo{grid.axis_center(first.x + offset.x) - 0.5 * res, grid.axis_center(first.y + offset.y) - 0.5 * res,
                 grid.axis_center(first.z + offset.z) - 0.5 * res};
  return {lo, Vec3d{lo.x + res, lo.y + res, lo.z + res}};
}

/// The end of pixel `pixel`'s ray (it has one).
Vec3d ray_end(const ProjectiveFrame& frame, std::size_t pixel) {
  const std::uint32_t k = frame.pixel_rays[pixel];
  return Vec3d(frame.ray_ends[frame.ray_order.empty() ? k : frame.ray_order[k]]);
}

}  // namespace

bool SurfaceBand::possible(double resolution, const ProjectiveFrame& frame, double max_range) {
  if (!frame.depth_halves.empty() || ProjectiveRule::seen_unit_depth(resolution, false) == 2) return false;
  // A voxel in the band lies at least z_min deep, within range, and has a reading beyond z_min - h.
  const double z_min = std::min(frame.fx, frame.fy) * resolution / (2.0 * kHalfWidthPixels);
  const double half_diagonal = std::sqrt(3.0) / 2.0 * resolution;
  if (max_range > 0.0 && z_min > max_range + half_diagonal) return false;
  const int top = frame.pyramid.levels() - 1;
  const float* top_max = frame.pyramid.level_max(top);
  float farthest = 0.0f;
  for (int i = 0; i < frame.pyramid.width(top) * frame.pyramid.height(top); ++i) farthest = std::max(farthest, top_max[i]);
  return farthest > z_min - half_diagonal;
}

std::optional<SurfaceBand> SurfaceBand::make(const ProjectiveRule& rule, std::shared_ptr<Image>* scratch) {
  const ProjectiveFrame& frame = *rule.frame;
  // Scans: not a depth image's rays (scan_images.hpp); fine resolutions: see the header.
  if (rule.seen_depth == 2 || rule.tree != nullptr || !possible(rule.grid->resolution(), frame, rule.max_range)) {
    return std::nullopt;
  }
  const std::size_t width = static_cast<std::size_t>(frame.width);
  const std::size_t height = static_cast<std::size_t>(frame.height);
  if (frame.pixel_rays.size() != width * height + 1) return std::nullopt;
  const double res = rule.grid->resolution();
  SurfaceBand band;
  band.half_depth = 0.5 * res * (std::abs(frame.rotation[2][0]) + std::abs(frame.rotation[2][1]) +
                                 std::abs(frame.rotation[2][2]));
  band.front_depth = band.half_depth + kFrontVoxels * res;
  for (std::size_t a = 0; a < 2; ++a) {
    band.half_width[a] = 0.5 * res * (std::abs(frame.rotation[a][0]) + std::abs(frame.rotation[a][1]) +
                                      std::abs(frame.rotation[a][2]));
    band.half_width_f[a] = static_cast<float>(band.half_width[a]);
  }
  // A voxel projects to about min(fx, fy) res / z pixels. Not nearer than
  // four half diagonals, so that the cubes lie well in front of the camera.
  band.z_min = std::max(std::min(frame.fx, frame.fy) * res / (2.0 * kHalfWidthPixels), 2.0 * std::sqrt(3.0) * res);
  band.z_min_f = static_cast<float>(band.z_min);
  band.footprint_scale = static_cast<float>(1.0 / (1.0 - band.half_depth / band.z_min) * (1.0 + 1e-6));
  band.half_depth_f = static_cast<float>(band.half_depth);
  band.front_depth_f = static_cast<float>(band.front_depth);

  std::shared_ptr<SurfaceBand::Image> image;
  if (scratch != nullptr && *scratch && scratch->use_count() == 1) {
    image = *scratch;
  } else {
    image = std::make_shared<SurfaceBand::Image>();
    if (scratch != nullptr) *scratch = image;
  }
  // The 3 x 3 minima and maxima: a row pass, then a column pass.
  std::vector<float>& row_min = image->row_min;
  std::vector<float>& row_max = image->row_max;
  row_min.resize(frame.depth.size());
  row_max.resize(frame.depth.size());
  for (std::size_t r = 0; r < height; ++r) {
    const float* in = frame.depth.data() + r * width;
    for (std::size_t c = 0; c < width; ++c) {
      float least = std::numeric_limits<float>::infinity();
      float largest = 0.0f;
      for (std::size_t k = c == 0 ? 0 : c - 1; k <= std::min(c + 1, width - 1); ++k) {
        if (in[k] > 0.0f) least = std::min(least, in[k]);
        largest = std::max(largest, in[k]);
      }
      row_min[r * width + c] = least;
      row_max[r * width + c] = largest;
    }
  }
  image->nearest.resize(frame.depth.size());
  image->farthest.resize(frame.depth.size());
  for (std::size_t r = 0; r < height; ++r) {
    for (std::size_t c = 0; c < width; ++c) {
      float least = std::numeric_limits<float>::infinity();
      float largest = 0.0f;
      for (std::size_t k = r == 0 ? 0 : r - 1; k <= std::min(r + 1, height - 1); ++k) {
        least = std::min(least, row_min[k * width + c]);
        largest = std::max(largest, row_max[k * width + c]);
      }
      image->nearest[r * width + c] = least;
      image->farthest[r * width + c] = largest;
    }
  }
  image->pyramid.build(image->nearest.data(), image->farthest.data(), frame.width, frame.height);

  // The rays, where they can reach a voxel of the band: their reading lies
  // beyond the nearest depth of its cubes (a ray ends at its reading or, cut
  // at max_range, before it).
  const float reaches = static_cast<float>(band.z_min - band.half_depth - 2.0 * depth_slack(band.z_min));
  image->rays.resize(width * height);
  for (std::size_t p = 0; p < width * height; ++p) {
    SurfaceBand::Image::Ray& ray = image->rays[p];
    ray.depth = 0.0f;
    if (frame.pixel_rays[p + 1] == frame.pixel_rays[p] || !(frame.depth[p] > reaches)) continue;
    UMBRA_ASSERT(frame.pixel_rays[p + 1] == frame.pixel_rays[p] + 1);  // a depth image: one ray a pixel
    ray.depth = frame.depth[p];
    // The direction as detail::segment_crosses computes it.
    Vec3d d = ray_end(frame, p) - frame.origin;
    const double length = d.norm();
    if (rule.max_range > 0.0 && length > rule.max_range) d = d * (rule.max_range / length);
    const double least = kLeastComponent * std::min(length, rule.max_range > 0.0 ? rule.max_range : length);
    if (!(std::abs(d.x) >= least && std::abs(d.y) >= least && std::abs(d.z) >= least && least > 0.0)) {
      ray.inverse[0] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    for (std::size_t a = 0; a < 3; ++a) ray.inverse[a] = static_cast<float>(1.0 / d[a]);
  }
  band.image = std::move(image);
  return band;
}

SurfaceBandBounds surface_band_bounds(const ProjectiveRule& rule, double near, double far, double u0, double u1,
                                      double v0, double v1) {
  if (!rule.surface_band) return {};
  const SurfaceBand& band = *rule.surface_band;
  const double slack = depth_slack(far);
  if (far + slack < band.z_min) return {};
  // A band voxel's 3 x 3 pixels are those around its own pixel, which lies
  // in the rectangle of the centres' pixels.
  const std::optional<PixelRect> rect = clip(*rule.frame, u0, u1, v0, v1);
  if (!rect) return {};
  const DepthPyramid::Range readings = band.image->pyramid.range(rect->u0, rect->v0, rect->u1, rect->v1);
  if (readings.max == 0.0f) return {};
  SurfaceBandBounds bounds;
  bounds.may_hold = near - band.half_depth - slack < readings.max && far + band.front_depth + slack >= readings.min;
  bounds.nearest = readings.min - slack;
  bounds.farthest = readings.max + slack;
  return bounds;
}

std::uint64_t surface_band_voxels(const ProjectiveRule& rule, Key first) {
  if (!rule.surface_band) return 0;
  std::array<BandVoxel, 64> voxels;
  const int count = band_voxels(rule, first, voxels);
  std::uint64_t mask = 0;
  for (int k = 0; k < count; ++k) mask |= std::uint64_t{1} << voxels[static_cast<std::size_t>(k)].index;
  return mask;
}

std::uint64_t apply_surface_band(const ProjectiveRule& rule, Key first, std::uint64_t cleared) {
  if (!rule.surface_band) return cleared;
  std::array<BandVoxel, 64> voxels;
  const int count = band_voxels(rule, first, voxels);
  if (count == 0) return cleared;
  const SurfaceBand& band = *rule.surface_band;
  const ProjectiveFrame& frame = *rule.frame;
  const Grid& grid = *rule.grid;
  const double res = grid.resolution();
  const SurfaceBand::Image::Ray* rays = band.image->rays.data();
  const int stride = frame.width;
  // The first voxel's cube minus the camera's position (the others' are
  // offsets of whole voxels from it): the float test's coordinates.
  const Vec3d first_lo{grid.axis_center(first.x) - 0.5 * res - frame.origin.x,
                       grid.axis_center(first.y) - 0.5 * res - frame.origin.y,
                       grid.axis_center(first.z) - 0.5 * res - frame.origin.z};
  for (int k = 0; k < count; ++k) {
    const BandVoxel& voxel = voxels[static_cast<std::size_t>(k)];
    // The footprint: the pixels whose rays (through u = column + 1/2) pass
    // within the bounds of the cube's projection: its camera-frame box is
    // the centre +- half_width (x, y) and +- h (z), so x / z lies within
    // (w + |x| / z h) / (z - h) of the centre's, and 1 / (z - h) is at most
    // footprint_scale / z. A fiftieth of a pixel wider for the float
    // arithmetic (its error is about 1e-3 pixel).
    const float scale = voxel.inverse * band.footprint_scale;
    const float extent_u =
        rule.fx * ((band.half_width_f[0] + std::abs(voxel.x) * voxel.inverse * band.half_depth_f) * scale) + 0.52f;
    const float extent_v =
        rule.fy * ((band.half_width_f[1] + std::abs(voxel.y) * voxel.inverse * band.half_depth_f) * scale) + 0.52f;
    // Columns c with u - extent_u <= c <= u + extent_u - 1 (extents hold the half pixel), in the image.
    const int u0 = ceil_at_least_zero(voxel.u - extent_u);
    const int u1 = std::min(floor_or_minus_one(voxel.u + extent_u - 1.0f), stride - 1);
    const int v0 = ceil_at_least_zero(voxel.v - extent_v);
    const int v1 = std::min(floor_or_minus_one(voxel.v + extent_v - 1.0f), frame.height - 1);
    // Rays ending before the cube's nearest depth cannot cross it.
    const float before = voxel.z - band.half_depth_f - static_cast<float>(depth_slack(voxel.z));
    const Key offset = morton::decode(voxel.index);
    const double lo_x = first_lo.x + offset.x * res;
    const double lo_y = first_lo.y + offset.y * res;
    const double lo_z = first_lo.z + offset.z * res;
    const float lo[3] = {static_cast<float>(lo_x), static_cast<float>(lo_y), static_cast<float>(lo_z)};
    const float hi[3] = {static_cast<float>(lo_x + res), static_cast<float>(lo_y + res), static_cast<float>(lo_z + res)};
    const auto crosses = [&](int column, int row) {
      const std::size_t pixel = static_cast<std::size_t>(row) * static_cast<std::size_t>(stride) +
                                static_cast<std::size_t>(column);
      const SurfaceBand::Image::Ray& ray = rays[pixel];
      if (!(ray.depth > before)) return false;
      const Crossing crossing = std::isnan(ray.inverse[0]) ? Crossing::unsure : crosses_in_float(lo, hi, ray.inverse);
      if (crossing != Crossing::unsure) return crossing == Crossing::yes;
      const Cube cube = cube_of(grid, first, voxel.index);
      return detail::segment_crosses(frame.origin, ray_end(frame, pixel), rule.max_range, cube.lo, cube.hi);
    };
    // The centre's own pixel first: most crossed voxels are crossed by its ray.
    const int own_u = static_cast<int>(voxel.u);
    const int own_v = static_cast<int>(voxel.v);
    const bool own_inside = own_u >= u0 && own_u <= u1 && own_v >= v0 && own_v <= v1;
    bool crossed = own_inside && crosses(own_u, own_v);
    for (int row = v0; row <= v1 && !crossed; ++row) {
      for (int column = u0; column <= u1 && !crossed; ++column) {
        if (column == own_u && row == own_v && own_inside) continue;
        crossed = crosses(column, row);
      }
    }
    const std::uint64_t bit = std::uint64_t{1} << voxel.index;
    cleared = crossed ? cleared | bit : cleared & ~bit;
  }
  return cleared;
}

std::uint64_t apply_surface_band_plain(const ProjectiveRule& rule, Key first, std::uint64_t cleared) {
  if (!rule.surface_band) return cleared;
  std::array<BandVoxel, 64> voxels;
  const int count = band_voxels(rule, first, voxels);
  const ProjectiveFrame& frame = *rule.frame;
  for (int k = 0; k < count; ++k) {
    const BandVoxel& voxel = voxels[static_cast<std::size_t>(k)];
    const Cube cube = cube_of(*rule.grid, first, voxel.index);
    // Every pixel's rays, but those whose reading lies before the cube's
    // nearest depth (they end before it).
    const double before = voxel.z - rule.surface_band->half_depth - depth_slack(voxel.z);
    bool crossed = false;
    for (std::size_t pixel = 0; pixel + 1 < frame.pixel_rays.size() && !crossed; ++pixel) {
      if (!(frame.depth[pixel] > before)) continue;
      for (std::uint32_t ray = frame.pixel_rays[pixel]; ray < frame.pixel_rays[pixel + 1] && !crossed; ++ray) {
        const Vec3d end(frame.ray_ends[frame.ray_order.empty() ? ray : frame.ray_order[ray]]);
        crossed = detail::segment_crosses(frame.origin, end, rule.max_range, cube.lo, cube.hi);
      }
    }
    const std::uint64_t bit = std::uint64_t{1} << voxel.index;
    cleared = crossed ? cleared | bit : cleared & ~bit;
  }
  return cleared;
}

}  // namespace umbra
