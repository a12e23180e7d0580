#include "integrate/projective_frame.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "umbra/core/morton.hpp"

namespace umbra {

namespace {

/// Projections beyond +-2^24 pixels are not seen (their cells would not be exact integers).
constexpr float kProjectionLimit = 16777216.0f;

}  // namespace

void ProjectiveFrame::set(const DepthImage& image, const PinholeCamera& camera, const Pose& pose) {
  camera.validate();
  if (!pose.is_rigid(1e-6)) {
    throw std::invalid_argument("the camera pose must be a rotation and a translation (an orthonormal 3x3 part with "
                                "determinant 1, all finite)");
  }
  width = image.width();
  height = image.height();
  depth.resize(image.pixel_count());
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<float>(image.depth(i));
  pyramid.build(depth.data(), width, height);
  fx = camera.fx;
  fy = camera.fy;
  cx = camera.cx;
  cy = camera.cy;
  // The pose maps camera to map: its 3x3 part's columns are the camera axes
  // in the map frame, so the rows of the inverse (its transpose) are.
  for (std::size_t r = 0; r < 3; ++r) {
    for (std::size_t c = 0; c < 3; ++c) rotation[r][c] = pose.m[c][r];
  }
  origin = pose.translation_d();
}

ProjectiveRule::ProjectiveRule(const Grid& grid_in, const ProjectiveFrame& frame_in, double max_range_in,
                               double margin_in, const std::optional<KeyBox>& box)
    : grid(&grid_in),
      frame(&frame_in),
      fx(static_cast<float>(frame_in.fx)),
      fy(static_cast<float>(frame_in.fy)),
      cx_half(static_cast<float>(frame_in.cx + 0.5)),
      cy_half(static_cast<float>(frame_in.cy + 0.5)),
      width(static_cast<float>(frame_in.width)),
      height(static_cast<float>(frame_in.height)),
      margin(static_cast<float>(margin_in)),
      max_range(max_range_in),
      half_voxel_pixels(static_cast<float>(frame_in.fx * grid_in.resolution() / 2.0)),
      top_level(frame_in.pyramid.levels() - 1),
      box_keys(box) {
  const double res = grid_in.resolution();
  for (unsigned i = 0; i < 64; ++i) {
    const Key k = morton::decode(i);
    const Vec3d offset = frame_in.rotate(Vec3d{k.x * res, k.y * res, k.z * res});
    for (std::size_t axis = 0; axis < 3; ++axis) offset_table[axis][i] = static_cast<float>(offset[axis]);
  }
  centre_dz = static_cast<float>(frame_in.rotate(Vec3d{1.5 * res, 1.5 * res, 1.5 * res}).z);
  if (max_range > 0.0) {
    const int ideal = static_cast<int>(std::lround(std::log2(max_range / 64.0 / res)));
    range_depth = ideal < 2 ? 0 : std::min(ideal, grid_in.depth_levels());
    if (range_depth == 0) max_range_squared = static_cast<float>(max_range * max_range);
  }
}

ProjectiveRule::CentreDistances ProjectiveRule::centre_distances(std::uint64_t code, int depth) const {
  const Key first = morton::decode(code);
  const double span = ((1u << depth) - 1) * grid->resolution();
  CentreDistances result{0.0, 0.0};
  for (std::size_t a = 0; a < 3; ++a) {
    const double below = grid->axis_center(first[a]) - frame->origin[a];
    const double above = below + span;
    const double nearest = below > 0.0 ? below : (above < 0.0 ? -above : 0.0);
    const double farthest = std::max(std::abs(below), std::abs(above));
    result.nearest_squared += nearest * nearest;
    result.farthest_squared += farthest * farthest;
  }
  return result;
}

bool ProjectiveRule::within_range(std::uint64_t code) const {
  if (max_range <= 0.0 || range_depth == 0) return true;
  const std::uint64_t node = code & ~((std::uint64_t{1} << (3 * range_depth)) - 1);
  return centre_distances(node, range_depth).farthest_squared <= max_range * max_range;
}

Vec3f ProjectiveRule::brick_origin(std::uint64_t brick) const {
  const Key k = morton::decode(brick);
  const Vec3d centre{grid->axis_center(k.x), grid->axis_center(k.y), grid->axis_center(k.z)};
  return Vec3f(frame->to_camera(centre));
}

int ProjectiveRule::window_level(Vec3f origin) const {
  const float z_ref = origin.z + centre_dz;
  if (!(z_ref > 0.0f)) return top_level;
  const float w = half_voxel_pixels / z_ref;
  if (!(w >= 1.0f)) return 0;
  const auto whole = static_cast<unsigned>(std::min(w, 1048576.0f));
  return std::min(static_cast<int>(std::bit_width(whole)), top_level);
}

std::uint64_t ProjectiveRule::cleared_plain(std::uint64_t brick) const {
  if (!within_range(brick)) return 0;
  const Vec3f base = brick_origin(brick);
  const int level = window_level(base);
  const float* cells = level == 0 ? frame->pyramid.level_max(0) : frame->pyramid.window_max(level);
  const int cells_wide = frame->pyramid.width(level);
  const int cells_high = frame->pyramid.height(level);
  const float scale = std::ldexp(1.0f, -level);  // exact: a power of two
  std::uint64_t result = 0;
  for (unsigned i = 0; i < 64; ++i) {
    const float x = base.x + offset_table[0][i];
    const float y = base.y + offset_table[1][i];
    const float z = base.z + offset_table[2][i];
    if (!(z > 0.0f)) continue;
    if (max_range_squared > 0.0f && !((x * x + y * y) + z * z <= max_range_squared)) continue;
    const float inverse = 1.0f / z;
    const float u = (x * inverse) * fx + cx_half;
    const float v = (y * inverse) * fy + cy_half;
    if (!(u >= -kProjectionLimit && u <= kProjectionLimit && v >= -kProjectionLimit && v <= kProjectionLimit)) continue;
    float d = 0.0f;
    if (level == 0) {
      if (!(u >= 0.0f && u < width && v >= 0.0f && v < height)) continue;
      d = cells[static_cast<std::size_t>(static_cast<int>(v)) * static_cast<std::size_t>(cells_wide) +
                static_cast<std::size_t>(static_cast<int>(u))];
    } else {
      // The window's first cell (a, b), and its maximum from window_max.
      const int a = static_cast<int>(std::floor(u * scale - 0.5f));
      const int b = static_cast<int>(std::floor(v * scale - 0.5f));
      if (a < -1 || b < -1 || a >= cells_wide || b >= cells_high) continue;
      d = cells[static_cast<std::size_t>(b + 1) * static_cast<std::size_t>(cells_wide + 1) +
                static_cast<std::size_t>(a + 1)];
    }
    if (z < d - margin) result |= std::uint64_t{1} << i;
  }
  return result;
}

std::uint64_t ProjectiveRule::cleared(std::uint64_t brick) const {
  static const bool avx2 = detail::projective_avx2_available();  // the CPU does not change
  if (!avx2) return cleared_plain(brick);
  if (!within_range(brick)) return 0;
  const Vec3f base = brick_origin(brick);
  return detail::projective_cleared_avx2(*this, base, window_level(base));
}

}  // namespace umbra
