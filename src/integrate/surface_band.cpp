#include "integrate/surface_band.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

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

/// Slack for the walk's bounds against this file's double arithmetic (the
/// centres the walk computes differ from these by rounding only).
double depth_slack(double far) { return 1e-5 * (1.0 + std::abs(far)); }

}  // namespace

bool SurfaceBand::possible(double resolution, const ProjectiveFrame& frame, double max_range) {
  if (ProjectiveRule::sees_whole_bricks(resolution) || !frame.depth_halves.empty()) return false;
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

std::optional<SurfaceBand> SurfaceBand::make(const ProjectiveRule& rule) {
  const ProjectiveFrame& frame = *rule.frame;
  // Scans: not a depth image's rays (scan_images.hpp); fine resolutions: see the header.
  if (rule.whole_bricks_seen || rule.tree != nullptr || !possible(rule.grid->resolution(), frame, rule.max_range)) {
    return std::nullopt;
  }
  if (frame.pixel_rays.size() != std::size_t(frame.width) * std::size_t(frame.height) + 1) return std::nullopt;
  const double res = rule.grid->resolution();
  SurfaceBand band;
  band.half_diagonal = std::sqrt(3.0) / 2.0 * res;
  band.half_depth = 0.5 * res * (std::abs(frame.rotation[2][0]) + std::abs(frame.rotation[2][1]) +
                                 std::abs(frame.rotation[2][2]));
  band.front_depth = band.half_depth + kFrontVoxels * res;
  for (std::size_t a = 0; a < 2; ++a) {
    band.half_width[a] = 0.5 * res * (std::abs(frame.rotation[a][0]) + std::abs(frame.rotation[a][1]) +
                                      std::abs(frame.rotation[a][2]));
  }
  // A voxel projects to about min(fx, fy) res / z pixels. Not nearer than
  // four half diagonals, so that the footprints stay bounded.
  band.z_min = std::max(std::min(frame.fx, frame.fy) * res / (2.0 * kHalfWidthPixels), 4.0 * band.half_diagonal);
  // The largest |x| / z and |y| / z of a centre projecting into the image.
  const double lateral = std::max(std::max(frame.cx + 0.5, frame.width - frame.cx - 0.5) / frame.fx,
                                  std::max(frame.cy + 0.5, frame.height - frame.cy - 0.5) / frame.fy);
  const double spread = band.half_diagonal * (1.0 + lateral) / (band.z_min - band.half_diagonal);
  band.reach_u = frame.fx * spread + 1.0;
  band.reach_v = frame.fy * spread + 1.0;
  auto readings = std::make_shared<SurfaceBand::Readings>();
  // The 3 x 3 minima and maxima: a row pass, then a column pass.
  const std::size_t width = static_cast<std::size_t>(frame.width);
  const std::size_t height = static_cast<std::size_t>(frame.height);
  std::vector<float> row_min(frame.depth.size());
  std::vector<float> row_max(frame.depth.size());
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
  readings->nearest.resize(frame.depth.size());
  readings->farthest.resize(frame.depth.size());
  for (std::size_t r = 0; r < height; ++r) {
    for (std::size_t c = 0; c < width; ++c) {
      float least = std::numeric_limits<float>::infinity();
      float largest = 0.0f;
      for (std::size_t k = r == 0 ? 0 : r - 1; k <= std::min(r + 1, height - 1); ++k) {
        least = std::min(least, row_min[k * width + c]);
        largest = std::max(largest, row_max[k * width + c]);
      }
      readings->nearest[r * width + c] = least;
      readings->farthest[r * width + c] = largest;
    }
  }
  readings->pyramid.build(readings->nearest.data(), readings->farthest.data(), frame.width, frame.height);
  band.readings = std::move(readings);
  return band;
}

SurfaceBandBounds surface_band_bounds(const ProjectiveRule& rule, double near, double far, double u0, double u1,
                                      double v0, double v1) {
  if (!rule.surface_band || far < rule.surface_band->z_min) return {};
  const SurfaceBand& band = *rule.surface_band;
  const ProjectiveFrame& frame = *rule.frame;
  const std::optional<PixelRect> rect = clip(frame, u0 - band.reach_u - 1.0, u1 + band.reach_u + 1.0,
                                             v0 - band.reach_v - 1.0, v1 + band.reach_v + 1.0);
  if (!rect) return {};
  const DepthPyramid::Range readings = band.readings->pyramid.range(rect->u0, rect->v0, rect->u1, rect->v1);
  if (readings.max == 0.0f) return {};
  const double slack = depth_slack(far);
  SurfaceBandBounds bounds;
  bounds.may_clear = near - band.half_depth - slack < readings.max;
  bounds.may_hold = bounds.may_clear && far + band.front_depth + slack >= readings.min;
  bounds.nearest = readings.min - slack;
  bounds.farthest = readings.max + slack;
  return bounds;
}

std::uint64_t apply_surface_band(const ProjectiveRule& rule, Key first, std::uint64_t cleared) {
  if (!rule.surface_band) return cleared;
  const SurfaceBand& band = *rule.surface_band;
  const ProjectiveFrame& frame = *rule.frame;
  const Grid& grid = *rule.grid;
  const double res = grid.resolution();
  // The brick's 64 centres span this box in the camera frame (corners c0 + offsets of 0 or 3 voxels).
  const Vec3d c0 = frame.to_camera(Vec3d{grid.axis_center(first.x), grid.axis_center(first.y), grid.axis_center(first.z)});
  const Vec3d ex = frame.rotate(Vec3d{res, 0.0, 0.0});
  const Vec3d ey = frame.rotate(Vec3d{0.0, res, 0.0});
  const Vec3d ez = frame.rotate(Vec3d{0.0, 0.0, res});
  double z_lo = std::numeric_limits<double>::infinity();
  double z_hi = -z_lo;
  for (unsigned i = 0; i < 8; ++i) {
    const double z = c0.z + (i & 1u ? 3.0 * ex.z : 0.0) + (i & 2u ? 3.0 * ey.z : 0.0) + (i & 4u ? 3.0 * ez.z : 0.0);
    z_lo = std::min(z_lo, z);
    z_hi = std::max(z_hi, z);
  }
  if (z_hi < band.z_min) return cleared;
  if (!rule.within_range(first)) return cleared;  // no voxel eligible (the rule clears none there either)
  const double fx = frame.fx;
  const double fy = frame.fy;
  const double u_offset = frame.cx + 0.5;
  const double v_offset = frame.cy + 0.5;
  // Bricks far from every reading: one pyramid read (every voxel's footprint
  // lies in the corners' pixels widened by the reach, as the walk's bounds).
  // The least and largest reading any voxel's footprint can hold.
  double brick_nearest = 0.0;
  double brick_farthest = std::numeric_limits<double>::infinity();
  if (z_lo > band.half_diagonal) {
    double u_lo = std::numeric_limits<double>::infinity();
    double u_hi = -u_lo;
    double v_lo = u_lo;
    double v_hi = -u_lo;
    for (unsigned i = 0; i < 8; ++i) {
      const Vec3d c = c0 + (i & 1u ? ex * 3.0 : Vec3d{}) + (i & 2u ? ey * 3.0 : Vec3d{}) + (i & 4u ? ez * 3.0 : Vec3d{});
      const double u = fx * (c.x / c.z) + u_offset;
      const double v = fy * (c.y / c.z) + v_offset;
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, v);
      v_hi = std::max(v_hi, v);
    }
    const SurfaceBandBounds bounds = surface_band_bounds(rule, z_lo, z_hi, u_lo, u_hi, v_lo, v_hi);
    if (!bounds.may_hold) return cleared;
    brick_nearest = bounds.nearest;
    brick_farthest = bounds.farthest;
  }
  const bool voxel_range = rule.max_range > 0.0 && rule.range_depth == 0;
  const double range_squared = rule.max_range * rule.max_range;
  const std::size_t stride = static_cast<std::size_t>(frame.width);
  for (unsigned i = 0; i < 64; ++i) {
    const Key offset = morton::decode(i);
    const Vec3d c = c0 + ex * double(offset.x) + ey * double(offset.y) + ez * double(offset.z);
    const double z = c.z;
    if (z < band.z_min) continue;
    if (z + band.front_depth < brick_nearest || z - band.half_depth >= brick_farthest) continue;  // as below, sooner
    const double inverse = 1.0 / z;
    const double u = fx * (c.x * inverse) + u_offset;
    const double v = fy * (c.y * inverse) + v_offset;
    if (!(u >= 0.0 && u < frame.width && v >= 0.0 && v < frame.height)) continue;
    if (voxel_range && c.x * c.x + c.y * c.y + z * z > range_squared) continue;
    // The readings of the 3 x 3 pixels around the centre's: whether the
    // voxel is near the surface.
    const std::size_t own = std::size_t(static_cast<int>(v)) * stride + std::size_t(static_cast<int>(u));
    const float nearest = band.readings->nearest[own];
    const float farthest = band.readings->farthest[own];
    if (farthest == 0.0f || !(z - band.half_depth < farthest && z + band.front_depth >= nearest)) continue;
    // The footprint P: the pixels whose centres (u + 1/2 in the rule's
    // coordinates, where the pixel's ray passes) lie within the bounds of
    // the cube's projection, a hundredth of a pixel wider for rounding.
    const double depth_inverse = 1.0 / (z - band.half_depth);
    const double extent_u = fx * (band.half_width[0] + std::abs(c.x) * inverse * band.half_depth) * depth_inverse;
    const double extent_v = fy * (band.half_width[1] + std::abs(c.y) * inverse * band.half_depth) * depth_inverse;
    const std::optional<PixelRect> rect = clip(frame, std::ceil(u - extent_u - 0.51), u + extent_u - 0.49,
                                               std::ceil(v - extent_v - 0.51), v + extent_v - 0.49);
    // In the band: cleared when a ray of P crosses the cube. Rays ending
    // before the cube's nearest depth cannot (a little slack for the end
    // points' float coordinates).
    const Key key{first.x + offset.x, first.y + offset.y, first.z + offset.z};
    const Vec3d lo{grid.axis_center(key.x) - 0.5 * res, grid.axis_center(key.y) - 0.5 * res,
                   grid.axis_center(key.z) - 0.5 * res};
    const Vec3d hi{lo.x + res, lo.y + res, lo.z + res};
    const double before = z - band.half_depth - depth_slack(z);
    bool crossed = false;
    for (int row = rect ? rect->v0 : 1; rect && row <= rect->v1 && !crossed; ++row) {
      for (int column = rect->u0; column <= rect->u1 && !crossed; ++column) {
        const std::size_t pixel = std::size_t(row) * stride + std::size_t(column);
        if (!(frame.depth[pixel] > before)) continue;
        for (std::uint32_t k = frame.pixel_rays[pixel]; k < frame.pixel_rays[pixel + 1] && !crossed; ++k) {
          const std::uint32_t ray = frame.ray_order.empty() ? k : frame.ray_order[k];
          crossed = detail::segment_crosses(frame.origin, Vec3d(frame.ray_ends[ray]), rule.max_range, lo, hi);
        }
      }
    }
    const std::uint64_t bit = std::uint64_t{1} << i;
    cleared = crossed ? cleared | bit : cleared & ~bit;
  }
  return cleared;
}

}  // namespace umbra
