#include "integrate/projective_frame.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/assert.hpp"
#include "umbra/core/morton.hpp"
#include "tree/update_batch.hpp"

namespace umbra {

namespace {

/// Projections beyond +-2^24 pixels are not seen (their cells would not be exact integers).
constexpr float kProjectionLimit = 16777216.0f;

/// Bricks this small or smaller are seen whole or not at all (see the header).
constexpr double kFinestSeenBorder = 0.02;
/// Groups of eight this small or smaller are seen whole or not at all (see the header).
constexpr double kGroupSeenBorder = 0.04;

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
  if (image.is_raw()) {  // one loop per kind, as back_project
    const std::span<const std::uint16_t> raw = image.raw_depths();
    const double scale = image.metres_per_unit();
    for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<float>(raw[i] * scale);
  } else {
    for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<float>(image.depth(i));
  }
  depth_halves.clear();
  pyramid.build(depth.data(), depth.data(), width, height);
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

void ProjectiveFrame::set_rays(std::span<const Vec3f> ends, std::span<const std::uint32_t> pixels) {
  ray_ends = ends;
  pixel_rays.assign(std::size_t(width) * std::size_t(height) + 1, 0);
  for (const std::uint32_t pixel : pixels) ++pixel_rays[pixel + 1];
  for (std::size_t p = 1; p < pixel_rays.size(); ++p) pixel_rays[p] += pixel_rays[p - 1];
  // A depth image's rays come in pixel order already (back_project): then
  // no order is kept. Otherwise, a counting sort of the rays by pixel.
  if (std::is_sorted(pixels.begin(), pixels.end())) {
    ray_order.clear();
    return;
  }
  ray_order.resize(pixels.size());
  std::vector<std::uint32_t> next(pixel_rays.begin(), pixel_rays.end() - 1);
  for (std::size_t i = 0; i < pixels.size(); ++i) ray_order[next[pixels[i]]++] = static_cast<std::uint32_t>(i);
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
      half_voxel_pixels(static_cast<float>(std::min(frame_in.fx, frame_in.fy) * grid_in.resolution() / 2.0)),
      top_level(frame_in.pyramid.levels() - 1),
      box_keys(box) {
  const double res = grid_in.resolution();
  for (unsigned i = 0; i < 64; ++i) {
    const Key k = morton::decode(i);
    const Vec3d offset = frame_in.rotate(Vec3d{k.x * res, k.y * res, k.z * res});
    for (std::size_t axis = 0; axis < 3; ++axis) offset_table[axis][i] = static_cast<float>(offset[axis]);
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    offset_min[axis] = *std::min_element(offset_table[axis].begin(), offset_table[axis].end());
    offset_max[axis] = *std::max_element(offset_table[axis].begin(), offset_table[axis].end());
  }
  centre_dz = static_cast<float>(frame_in.rotate(Vec3d{1.5 * res, 1.5 * res, 1.5 * res}).z);
  seen_depth = seen_unit_depth(res, !frame_in.depth_halves.empty());
  edge_reach = half_voxel_pixels;
  width_inside = width - 0.5f;
  height_inside = height - 0.5f;
  if (max_range > 0.0) {
    const int ideal = static_cast<int>(std::lround(std::log2(max_range / 64.0 / res)));
    range_depth = ideal < 2 ? 0 : std::min(ideal, grid_in.depth_levels());
    if (range_depth == 0) max_range_squared = static_cast<float>(max_range * max_range);
  }
}

int ProjectiveRule::seen_unit_depth(double resolution, bool scan_image) {
  if (4.0 * resolution <= kFinestSeenBorder) return 2;
  return !scan_image && 2.0 * resolution <= kGroupSeenBorder * (1.0 + 1e-9) ? 1 : 0;
}

std::uint64_t ProjectiveRule::keep_seen_units(std::uint64_t cleared, std::uint64_t seen, int seen_depth) {
  if (seen_depth == 0) return cleared;
  if (seen_depth == 2) return seen == ~std::uint64_t{0} ? cleared : 0;
  // Bit 8 j of `whole` ends up set when the eight bits 8 j to 8 j + 7 of
  // `seen` are (group j, the depth-1 node of voxels 8 j to 8 j + 7, all seen).
  std::uint64_t whole = seen & (seen >> 1);
  whole &= whole >> 2;
  whole &= whole >> 4;
  return cleared & ((whole & 0x0101010101010101u) * 0xFFu);
}

void ProjectiveRule::use_cells(double widest) {
  cells.clear();
  if (seen_depth != 2 || tree != nullptr) return;
  for (int c = 1; std::ldexp(grid->resolution(), c) <= widest * (1.0 + 1e-9); ++c) {
    if (grid->depth_levels() - c < 3) break;                     // a coarse grid with bricks and room above them
    if (max_range > 0.0 && range_depth != 0 && range_depth < 2 + c) break;  // the range node would split the node
    auto level = std::make_shared<CellLevel>(*grid, c, *frame, margin);  // margin: the same float
    ProjectiveRule& coarse = level->rule;
    coarse.edge_reach = edge_reach;
    coarse.seen_depth = 2;
    // The finest grid's range: per node in add_cell_misses, or voxel by voxel on the cells' centres.
    coarse.max_range_squared = range_depth == 0 ? max_range_squared : 0.0f;
    cells.push_back(std::move(level));
  }
}

bool ProjectiveRule::decided_by_cells(Key first, int depth) const {
  const int c = depth - 2;
  if (c < 1 || c > static_cast<int>(cells.size())) return false;
  const ProjectiveRule& coarse = cells[static_cast<std::size_t>(c - 1)]->rule;
  const Vec3f origin = coarse.brick_origin(Key{first.x >> c, first.y >> c, first.z >> c});
  const float z_ref = origin.z + coarse.centre_dz;
  return z_ref > 0.0f && coarse.half_voxel_pixels / z_ref < kCellPixels / 2.0f;
}

std::uint64_t ProjectiveRule::brick_voxels_in_box(std::uint64_t brick) const {
  if (!box_keys) return ~std::uint64_t{0};
  const Key low = morton::decode(brick);
  const Key high{low.x + 3, low.y + 3, low.z + 3};
  if (box_keys->contains(low) && box_keys->contains(high)) return ~std::uint64_t{0};
  std::uint64_t mask = 0;
  for (unsigned i = 0; i < 64; ++i) mask |= std::uint64_t{box_keys->contains(morton::decode(brick + i))} << i;
  return mask;
}

void ProjectiveRule::add_cell_misses(std::uint64_t node, Key first, int depth, bool plain, UpdateBatch& batch) const {
  const int c = depth - 2;
  UMBRA_ASSERT(c >= 1 && c <= static_cast<int>(cells.size()) && (node & ((std::uint64_t{1} << (3 * depth)) - 1)) == 0);
  if (!within_range(first)) return;  // its range node holds the whole node (use_cells)
  const ProjectiveRule& coarse = cells[static_cast<std::size_t>(c - 1)]->rule;
  const std::uint64_t brick = node >> (3 * c);  // the node as a brick of the coarse grid
  const std::uint64_t cleared =
      plain ? coarse.cleared_plain(brick) : coarse.cleared_in_range(brick, Key{first.x >> c, first.y >> c, first.z >> c});
  if (cleared == 0) return;
  if (c == 1) {
    // Cell i is the depth-1 node node + 8 i: brick i / 8, its depth-1 node i % 8.
    for (std::uint64_t b = 0; b < 8; ++b) {
      const std::uint64_t byte = (cleared >> (8 * b)) & 0xFFu;
      std::uint64_t voxels = 0;
      for (unsigned j = 0; j < 8; ++j) voxels |= ((byte >> j) & 1u) * (std::uint64_t{0xFF} << (8 * j));
      if (voxels != 0) voxels &= brick_voxels_in_box(node + 64 * b);
      if (voxels != 0) batch.add_misses_in_brick(node + 64 * b, voxels);
    }
    return;
  }
  // Cell i is the depth-c node node + i 8^c; cells 8 j to 8 j + 7 make up
  // the depth-(c + 1) node j, marked as one where all eight are cleared.
  const auto add = [&](std::uint64_t first_voxel, int node_depth) {
    const std::uint64_t voxels = std::uint64_t{1} << (3 * node_depth);
    if (!box_keys ||
        (box_keys->contains(morton::decode(first_voxel)) && box_keys->contains(morton::decode(first_voxel + voxels - 1)))) {
      batch.add_miss_node(first_voxel, node_depth);
      return;
    }
    for (std::uint64_t b = first_voxel; b < first_voxel + voxels; b += 64) {
      const std::uint64_t in_box = brick_voxels_in_box(b);
      if (in_box != 0) batch.add_misses_in_brick(b, in_box);
    }
  };
  const std::uint64_t cell_voxels = std::uint64_t{1} << (3 * c);
  for (std::uint64_t j = 0; j < 8; ++j) {
    const std::uint64_t byte = (cleared >> (8 * j)) & 0xFFu;
    if (byte == 0xFFu) {
      add(node + 8 * j * cell_voxels, c + 1);
      continue;
    }
    for (std::uint64_t rest = byte; rest != 0; rest &= rest - 1) {
      add(node + (8 * j + static_cast<std::uint64_t>(std::countr_zero(rest))) * cell_voxels, c);
    }
  }
}

ProjectiveRule::CentreDistances ProjectiveRule::centre_distances(Key first, int depth) const {
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

bool ProjectiveRule::within_range(Key voxel) const {
  if (max_range <= 0.0 || range_depth == 0) return true;
  const std::uint32_t low = ~((std::uint32_t{1} << range_depth) - 1);
  const Key node{voxel.x & low, voxel.y & low, voxel.z & low};
  return centre_distances(node, range_depth).farthest_squared <= max_range * max_range;
}

Vec3f ProjectiveRule::brick_origin(Key k) const {
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

namespace detail {

bool segment_crosses(Vec3d o, Vec3d end, double max_range, Vec3d lo, Vec3d hi) {
  Vec3d d = end - o;
  const double length = d.norm();
  if (max_range > 0.0 && length > max_range) {  // truncated, as the integrators truncate it
    d = d * (max_range / length);
    end = o + d;
  }
  if (end.x >= lo.x && end.x < hi.x && end.y >= lo.y && end.y < hi.y && end.z >= lo.z && end.z < hi.z) {
    return false;  // the ray ends in the voxel: a hit there, not a miss
  }
  // Slab test: the segment o + t d, t in [0, 1], against the cube.
  double enter = 0.0;
  double leave = 1.0;
  for (std::size_t a = 0; a < 3 && enter <= leave; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] >= hi[a]) leave = -1.0;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a];
    double t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
  }
  return enter < leave;
}

}  // namespace detail

bool ProjectiveRule::ray_crosses(std::uint64_t code) const {
  const Key key = morton::decode(code);
  const double res = grid->resolution();
  const Vec3d lo{grid->axis_center(key.x) - 0.5 * res, grid->axis_center(key.y) - 0.5 * res,
                 grid->axis_center(key.z) - 0.5 * res};
  const Vec3d hi{lo.x + res, lo.y + res, lo.z + res};
  // The pixels the voxel's cube projects onto (a pixel's rays leave the
  // camera through it), one more on every side for rounding.
  double u_min = 1e300;
  double u_max = -1e300;
  double v_min = 1e300;
  double v_max = -1e300;
  for (unsigned i = 0; i < 8; ++i) {
    const Vec3d c = frame->to_camera(Vec3d{i & 1u ? hi.x : lo.x, i & 2u ? hi.y : lo.y, i & 4u ? hi.z : lo.z});
    if (!(c.z > 1e-9)) return false;  // at or behind the camera plane: kept (no ray is known to cross it)
    const double u = frame->fx * (c.x / c.z) + frame->cx + 0.5;
    const double v = frame->fy * (c.y / c.z) + frame->cy + 0.5;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  const int u0 = static_cast<int>(std::max(std::floor(u_min) - 1.0, 0.0));
  const int v0 = static_cast<int>(std::max(std::floor(v_min) - 1.0, 0.0));
  const int u1 = static_cast<int>(std::min(std::floor(u_max) + 1.0, frame->width - 1.0));
  const int v1 = static_cast<int>(std::min(std::floor(v_max) + 1.0, frame->height - 1.0));
  if (u0 > u1 || v0 > v1) return false;
  auto pixel_crosses = [&](int u, int v) {
    const std::size_t pixel = std::size_t(v) * std::size_t(frame->width) + std::size_t(u);
    for (std::uint32_t k = frame->pixel_rays[pixel]; k < frame->pixel_rays[pixel + 1]; ++k) {
      const std::uint32_t ray = frame->ray_order.empty() ? k : frame->ray_order[k];
      if (detail::segment_crosses(frame->origin, Vec3d(frame->ray_ends[ray]), max_range, lo, hi)) return true;
    }
    return false;
  };
  // The rays of the 3 x 3 pixels in the middle of the footprint, the middle
  // one first: a voxel larger than that (near the camera) is crossed in its
  // middle if at all, and testing every pixel under it cost 2,000
  // instructions an obstacle (TUM at 2 cm: 40% of the misses' time).
  const int middle_u = (u0 + u1) / 2;
  const int middle_v = (v0 + v1) / 2;
  if (pixel_crosses(middle_u, middle_v)) return true;
  for (int v = std::max(v0, middle_v - 1); v <= std::min(v1, middle_v + 1); ++v) {
    for (int u = std::max(u0, middle_u - 1); u <= std::min(u1, middle_u + 1); ++u) {
      if ((u != middle_u || v != middle_v) && pixel_crosses(u, v)) return true;
    }
  }
  return false;
}

std::uint64_t ProjectiveRule::cleared_plain(std::uint64_t brick) const {
  const VoxelVerdicts verdicts = voxel_verdicts(brick);
  return keep_seen_units(verdicts.cleared, verdicts.seen, seen_depth);
}

ProjectiveRule::VoxelVerdicts ProjectiveRule::voxel_verdicts(std::uint64_t brick) const {
  const Key first = morton::decode(brick);
  if (!within_range(first)) return {0, 0};
  const Vec3f base = brick_origin(first);
  const int level = window_level(base);
  const float* readings = level == 0 ? frame->depth.data() : frame->pyramid.window_max(level);
  const int cells_wide = frame->pyramid.width(level);
  const float scale = DepthPyramid::pixel_cells(level);
  std::uint64_t result = 0;
  std::uint64_t seen = 0;
  for (unsigned i = 0; i < 64; ++i) {
    const float x = base.x + offset_table[0][i];
    const float y = base.y + offset_table[1][i];
    const float z = base.z + offset_table[2][i];
    if (!(z > 0.0f)) continue;
    if (max_range_squared > 0.0f && !((x * x + y * y) + z * z <= max_range_squared)) continue;
    const float inverse = 1.0f / z;
    const float u_free = (x * inverse) * fx + cx_half;
    const float v_free = (y * inverse) * fy + cy_half;
    if (!(u_free >= -kProjectionLimit && u_free <= kProjectionLimit && v_free >= -kProjectionLimit &&
          v_free <= kProjectionLimit)) {
      continue;
    }
    // Within the edge reach of the image: the nearest pixel's (or window's) reading.
    const float reach = edge_reach * inverse;
    if (!(u_free >= -reach && u_free < width + reach && v_free >= -reach && v_free < height + reach)) continue;
    const float u = std::min(std::max(u_free, 0.0f), width_inside);
    const float v = std::min(std::max(v_free, 0.0f), height_inside);
    float d = 0.0f;
    if (level == 0 && !frame->depth_halves.empty()) {
      // Its half pixel's reading: the half's nearest, else its pixel's (u + u and v + v are exact).
      d = frame->depth_halves[static_cast<std::size_t>(static_cast<int>(v + v)) * static_cast<std::size_t>(2 * cells_wide) +
                              static_cast<std::size_t>(static_cast<int>(u + u))];
    } else if (level == 0) {
      d = readings[static_cast<std::size_t>(static_cast<int>(v)) * static_cast<std::size_t>(cells_wide) +
                static_cast<std::size_t>(static_cast<int>(u))];
    } else {
      // The window's first cell (a, b), and its maximum from window_max.
      const int a = static_cast<int>(std::floor(u * scale - 0.5f));
      const int b = static_cast<int>(std::floor(v * scale - 0.5f));
      d = readings[static_cast<std::size_t>(b + 1) * static_cast<std::size_t>(cells_wide + 1) +
                static_cast<std::size_t>(a + 1)];
    }
    if (d > 0.0f) seen |= std::uint64_t{1} << i;
    if (z < d - margin) result |= std::uint64_t{1} << i;
  }
  return {result, seen};
}

std::uint64_t ProjectiveRule::cleared(std::uint64_t brick) const {
  const Key first = morton::decode(brick);
  return within_range(first) ? cleared_in_range(brick, first) : 0;
}

std::uint64_t ProjectiveRule::cleared_in_range(std::uint64_t brick, Key first) const {
  static const bool avx2 = detail::projective_avx2_available();  // the CPU does not change
  const Vec3f base = brick_origin(first);
  const int level = window_level(base);
  // Most bricks a walk reaches are cleared whole or not at all (TUM at 4 mm:
  // 36% and 54%): bounds decide those for a tenth of a voxel-by-voxel pass.
  if (const std::optional<std::uint64_t> whole = whole_brick(base, level)) return *whole;
  if (!avx2) return cleared_plain(brick);
  return detail::projective_cleared_avx2(*this, base, level);
}

// Why the bounds hold. Each voxel's float coordinate is fl(origin + offset),
// and rounding is monotonic, so it lies between fl(origin + least offset)
// and fl(origin + largest offset). Likewise 1 / z lies between the bounds'
// reciprocals; x (1 / z) between the least and largest of the four corner
// products (the exact product of two intervals is extreme at a corner, and
// rounding keeps the order); then times fx > 0 plus cx; the clamp into the
// image, truncation and floor are monotonic too. So every voxel reads a
// cell inside the rectangle spanned by the bounds' cells, and its reading
// lies between the rectangle's least and largest. (The build forbids
// contracting a * b + c into one rounding, which would break the equality
// with cleared_plain as well.)
std::optional<std::uint64_t> ProjectiveRule::whole_brick(Vec3f origin, int level) const {
  constexpr std::optional<std::uint64_t> undecided;
  const float x_lo = origin.x + offset_min[0];
  const float x_hi = origin.x + offset_max[0];
  const float y_lo = origin.y + offset_min[1];
  const float y_hi = origin.y + offset_max[1];
  const float z_lo = origin.z + offset_min[2];
  const float z_hi = origin.z + offset_max[2];
  if (!(z_hi > 0.0f)) return 0;  // behind the camera: no voxel is seen
  // Near the camera plane the reciprocals grow without bound: left to the voxels.
  if (!(z_lo > 1e-6f)) return undecided;
  bool all_in_range = true;
  if (max_range_squared > 0.0f) {
    const auto largest_square = [](float lo, float hi) {
      const float a = std::max(std::abs(lo), std::abs(hi));
      return a * a;
    };
    const auto least_square = [](float lo, float hi) {
      const float a = lo > 0.0f ? lo : (hi < 0.0f ? -hi : 0.0f);
      return a * a;
    };
    const float nearest = (least_square(x_lo, x_hi) + least_square(y_lo, y_hi)) + least_square(z_lo, z_hi);
    if (!(nearest <= max_range_squared)) return 0;  // no voxel within range
    const float farthest = (largest_square(x_lo, x_hi) + largest_square(y_lo, y_hi)) + largest_square(z_lo, z_hi);
    all_in_range = farthest <= max_range_squared;
  }
  const float inverse_lo = 1.0f / z_hi;
  const float inverse_hi = 1.0f / z_lo;
  struct Interval {
    float lo;
    float hi;
  };
  const auto projection = [&](float lo, float hi, float focal, float centre) {
    const float a = lo * inverse_lo;
    const float b = lo * inverse_hi;
    const float c = hi * inverse_lo;
    const float d = hi * inverse_hi;
    return Interval{std::min(std::min(a, b), std::min(c, d)) * focal + centre,
                    std::max(std::max(a, b), std::max(c, d)) * focal + centre};
  };
  const Interval u = projection(x_lo, x_hi, fx, cx_half);
  const Interval v = projection(y_lo, y_hi, fy, cy_half);
  // Beyond the edge reach on one side (the largest reach is the nearest
  // voxel's): no voxel is seen.
  const float reach = edge_reach * inverse_hi;
  if (u.hi < -reach || v.hi < -reach || u.lo >= width + reach || v.lo >= height + reach) return 0;
  // The cells the voxels can read (cleared_plain: clamped into the image first).
  const auto clamp_u = [&](float value) { return std::min(std::max(value, 0.0f), width_inside); };
  const auto clamp_v = [&](float value) { return std::min(std::max(value, 0.0f), height_inside); };
  const float* lowest;   // the cells' least readings
  const float* highest;  // and largest
  int stride;
  int u0, u1, v0, v1;
  if (level == 0) {
    lowest = frame->depth.data();  // a scan's half pixels read no nearer than their pixel's nearest
    highest = frame->pyramid.level_max(0);
    stride = frame->width;
    u0 = static_cast<int>(clamp_u(u.lo));
    u1 = static_cast<int>(clamp_u(u.hi));
    v0 = static_cast<int>(clamp_v(v.lo));
    v1 = static_cast<int>(clamp_v(v.hi));
  } else {
    // window_max's entry (b + 1) (width + 1) + (a + 1) for window (a, b).
    lowest = highest = frame->pyramid.window_max(level);
    stride = frame->pyramid.width(level) + 1;
    const float scale = DepthPyramid::pixel_cells(level);
    u0 = static_cast<int>(std::floor(clamp_u(u.lo) * scale - 0.5f)) + 1;
    u1 = static_cast<int>(std::floor(clamp_u(u.hi) * scale - 0.5f)) + 1;
    v0 = static_cast<int>(std::floor(clamp_v(v.lo) * scale - 0.5f)) + 1;
    v1 = static_cast<int>(std::floor(clamp_v(v.hi) * scale - 0.5f)) + 1;
  }
  // Wide footprints (near the camera) are left to the voxels. A brick whose
  // voxels read their own pixels spans at most about 9 x 9 of them, and one
  // whose voxels read windows about as many windows.
  if ((u1 - u0 + 1) * (v1 - v0 + 1) > 100) return undecided;
  float least = std::numeric_limits<float>::infinity();
  float largest = 0.0f;
  detail::rectangle_min_max(lowest, highest, stride, u0, u1, v0, v1, least, largest);
  // No voxel nearer than every reading's d - margin: none cleared.
  if (z_lo >= largest - margin) return 0;
  // Every voxel seen (inside the image, in range) and nearer than every reading: all cleared.
  const bool inside = u.lo >= 0.0f && u.hi < width && v.lo >= 0.0f && v.hi < height;
  if (inside && all_in_range && z_hi < least - margin) return ~std::uint64_t{0};
  return undecided;
}

}  // namespace umbra
