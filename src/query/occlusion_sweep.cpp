#include "query/occlusion_sweep.hpp"

#include <algorithm>
#include <cmath>

namespace umbra::detail {
namespace {

/// The bits of `open` reachable from the bits of `reach` by moving to
/// higher bits through set bits of `open` (a Kogge-Stone fill).
std::uint64_t fill_up(std::uint64_t reach, std::uint64_t open) {
  std::uint64_t g = reach & open;
  std::uint64_t p = open;
  g |= p & (g << 1);
  p &= p << 1;
  g |= p & (g << 2);
  p &= p << 2;
  g |= p & (g << 4);
  p &= p << 4;
  g |= p & (g << 8);
  p &= p << 8;
  g |= p & (g << 16);
  p &= p << 16;
  g |= p & (g << 32);
  return g;
}

/// The same towards lower bits.
std::uint64_t fill_down(std::uint64_t reach, std::uint64_t open) {
  std::uint64_t g = reach & open;
  std::uint64_t p = open;
  g |= p & (g >> 1);
  p &= p >> 1;
  g |= p & (g >> 2);
  p &= p >> 2;
  g |= p & (g >> 4);
  p &= p >> 4;
  g |= p & (g >> 8);
  p &= p >> 8;
  g |= p & (g >> 16);
  p &= p >> 16;
  g |= p & (g >> 32);
  return g;
}

/// Moves along a row: towards higher keys (+1), lower (-1) or both (0).
std::uint64_t fill_row(std::uint64_t reach, std::uint64_t open, int direction) {
  if (direction > 0) return fill_up(reach, open);
  if (direction < 0) return fill_down(reach, open);
  for (;;) {
    const std::uint64_t next = fill_down(fill_up(reach, open), open);
    if (next == reach) return reach;
    reach = next;
  }
}

/// +1 when every slope in [low, high] is >= 0 (walks step only up the
/// axis), -1 when every one is <= 0, else 0.
int direction_of(double low, double high) { return low >= 0.0 ? 1 : (high <= 0.0 ? -1 : 0); }

}  // namespace

bool OcclusionSweep::hidden(const Pose& pose, const Aabb& targets, double obstacle_free) {
  const Grid& grid = *pose.grid;
  const double res = grid.resolution();
  const double inverse = 1.0 / res;
  const Vec3d o = pose.apex;
  const double m = pose.margin;
  // The sweep axis: one along which every target lies beyond the apex, the
  // one where they lie farthest (the thinnest cross-sections).
  int a = -1;
  int s = 0;
  double best = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double ahead = targets.min[axis] - o[axis];
    const double behind = o[axis] - targets.max[axis];
    if (ahead > best) {
      best = ahead;
      a = axis;
      s = 1;
    }
    if (behind > best) {
      best = behind;
      a = axis;
      s = -1;
    }
  }
  if (a < 0) return false;
  // Rows run along b, x whenever possible (the bitmap's rows).
  const int b = a == 0 ? 1 : 0;
  const int c = 3 - a - b;
  const std::int64_t offset = grid.key_offset();
  const std::int64_t last = std::int64_t{grid.keys_per_axis()} - 1;
  auto key_of = [&](double x) {
    return std::clamp(static_cast<std::int64_t>(std::floor(x * inverse)) + offset, std::int64_t{0}, last);
  };

  // The cone's edges: across-axis offset per unit along a, and the longest
  // distance per unit along a.
  // (The extremes over the box's corners: along a, the box's near and far
  // faces; across, its two faces on each axis.)
  double low_b = INFINITY, high_b = -INFINITY, low_c = INFINITY, high_c = -INFINITY, secant2 = 0.0;
  for (const double face_a : {targets.min[a], targets.max[a]}) {
    const double inverse_along = 1.0 / std::fabs(face_a - o[a]);
    for (const double face_b : {targets.min[b], targets.max[b]}) {
      const double slope_b = (face_b - o[b]) * inverse_along;
      low_b = std::min(low_b, slope_b);
      high_b = std::max(high_b, slope_b);
      for (const double face_c : {targets.min[c], targets.max[c]}) {
        const double slope_c = (face_c - o[c]) * inverse_along;
        secant2 = std::max(secant2, 1.0 + slope_b * slope_b + slope_c * slope_c);
      }
    }
    for (const double face_c : {targets.min[c], targets.max[c]}) {
      const double slope_c = (face_c - o[c]) * inverse_along;
      low_c = std::min(low_c, slope_c);
      high_c = std::max(high_c, slope_c);
    }
  }
  // A hair more than the exact value, for its rounding.
  const double secant = std::sqrt(secant2) * (1.0 + 1e-12);
  // Within a layer walks step only the way their direction points.
  const int along_b = direction_of(low_b, high_b);
  const int along_c = direction_of(low_c, high_c);

  // Layers strictly between the apex's and the nearest target's.
  const std::int64_t apex_layer = pose.apex_key[a];
  const std::int64_t end_layer = key_of(s > 0 ? targets.min[a] : targets.max[a]);
  // Distance along a (in the walks' direction) of a layer's near face.
  auto near_face = [&](std::int64_t k) {
    return s > 0 ? double(k - offset) * res - o[a] : o[a] - double(k - offset + 1) * res;
  };
  // Start at the first layer whose part of the cone may hold an obstacle
  // (the layers before are taken as wholly reachable): the points of the
  // cone (grown by the margin) in layer k lie within
  // (far face + margin) * secant + margin of the apex.
  const double clear_along = (obstacle_free - m) / secant - m;  // layers ending before this are clear
  std::int64_t layer = apex_layer + s;
  if (clear_along > 0.0) {
    const double steps = std::floor((clear_along - near_face(apex_layer + s)) * inverse);
    if (steps > 1.0) layer += s * static_cast<std::int64_t>(std::min(steps - 1.0, 1e9));
  }
  const OccupiedBitmap& occupied = *pose.occupied;
  Layer before;
  Layer current;
  bool before_all_reachable = true;
  std::array<std::uint64_t, kMaxWidth> open{};
  for (int swept = 0; swept < kMaxLayers && (layer - end_layer) * s < 0; ++swept, layer += s) {
    const double t0 = std::max(0.0, near_face(layer) - m);
    const double t1 = near_face(layer) + res + m;
    auto range = [&](double low_slope, double high_slope, double origin, std::int64_t& k0, std::int64_t& k1) {
      k0 = key_of(origin + std::min(t0 * low_slope, t1 * low_slope) - m);
      k1 = key_of(origin + std::max(t0 * high_slope, t1 * high_slope) + m);
    };
    range(low_b, high_b, o[b], current.b0, current.b1);
    range(low_c, high_c, o[c], current.c0, current.c1);
    if (current.b1 - current.b0 >= kMaxWidth || current.c1 - current.c0 >= kMaxWidth) return false;
    const int width = static_cast<int>(current.b1 - current.b0 + 1);
    const int rows = static_cast<int>(current.c1 - current.c0 + 1);
    const std::uint64_t row_mask = width == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << width) - 1;
    // Which voxels of the layer a walk may pass (not occupied), and where
    // walks come in from the layer before.
    std::int64_t at[3];
    at[a] = layer;
    bool any = false;
    for (int row = 0; row < rows; ++row) {
      at[c] = current.c0 + row;
      std::uint64_t blocked = 0;
      if (b == 0) {
        blocked = occupied.row(current.b0, width, at[1], at[2]);
      } else {
        for (int i = 0; i < width; ++i) {
          at[b] = current.b0 + i;
          if (occupied.occupied(at[0], at[1], at[2])) blocked |= std::uint64_t{1} << i;
        }
      }
      const std::uint64_t bits = ~blocked & row_mask;
      open[std::size_t(row)] = bits;
      std::uint64_t seeds = bits;
      if (!before_all_reachable) {
        const std::int64_t before_row = current.c0 + row - before.c0;
        seeds = 0;
        if (before_row >= 0 && before_row <= before.c1 - before.c0) {
          const std::int64_t shift = before.b0 - current.b0;  // bit i of before is bit i + shift here
          const std::uint64_t from = before.reach[std::size_t(before_row)];
          seeds = shift >= 64 || shift <= -64 ? 0 : (shift >= 0 ? from << shift : from >> -shift);
        }
      }
      current.reach[std::size_t(row)] = seeds & bits;
      any |= (seeds & bits) != 0;
    }
    if (!any) return true;
    // Within the layer: from voxel to face neighbour the way walks step,
    // row by row in the walks' direction along c (both ways: until stable).
    for (bool changed = true; changed;) {
      changed = false;
      for (int pass = 0; pass < 2; ++pass) {
        const int direction = pass == 0 ? 1 : -1;
        if (along_c == -direction) continue;
        for (int i = 0; i < rows; ++i) {
          const int row = direction > 0 ? i : rows - 1 - i;
          const int from = row - direction;
          std::uint64_t r = current.reach[std::size_t(row)];
          if (from >= 0 && from < rows) r |= current.reach[std::size_t(from)];
          r = fill_row(r, open[std::size_t(row)], along_b);
          if (r != current.reach[std::size_t(row)]) {
            current.reach[std::size_t(row)] = r;
            changed = true;
          }
        }
      }
      if (along_c != 0) break;  // one pass in the walks' direction reaches everything
    }
    std::swap(before, current);
    before_all_reachable = false;
  }
  return false;
}

}  // namespace umbra::detail
