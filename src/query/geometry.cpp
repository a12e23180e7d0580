#include "query/geometry.hpp"

#include <algorithm>
#include <limits>

namespace umbra::detail {
namespace {

Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

}  // namespace

double point_segment_distance_squared(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d d = b - a;
  const double length2 = d.dot(d);
  double t = length2 > 0.0 ? (p - a).dot(d) / length2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const Vec3d closest = a + d * t;
  const Vec3d e = p - closest;
  return e.dot(e);
}

double segment_box_distance_squared(Vec3d a, Vec3d b, const Aabb& box) {
  // f(t) = squared distance from a + t (b - a) to the box is convex and
  // quadratic between the t where the point crosses a face plane: minimise
  // the quadratic on each such piece of [0, 1].
  const Vec3d d = b - a;
  std::array<double, 8> cuts{};
  int n = 0;
  cuts[n++] = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] == 0.0) continue;
    for (const double plane : {box.min[axis], box.max[axis]}) {
      const double t = (plane - a[axis]) / d[axis];
      if (t > 0.0 && t < 1.0) cuts[n++] = t;
    }
  }
  cuts[n++] = 1.0;
  std::sort(cuts.begin(), cuts.begin() + n);
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i + 1 < n; ++i) {
    const double t0 = cuts[i];
    const double t1 = cuts[i + 1];
    // On this piece each axis is below, inside or above the box throughout:
    // its distance is c + k t (or 0). Minimise sum (c + k t)^2.
    const double mid = 0.5 * (t0 + t1);
    double sum_ck = 0.0;
    double sum_kk = 0.0;
    std::array<double, 3> c{};
    std::array<double, 3> k{};
    for (int axis = 0; axis < 3; ++axis) {
      const double p = a[axis] + mid * d[axis];
      if (p < box.min[axis]) {
        c[axis] = box.min[axis] - a[axis];
        k[axis] = -d[axis];
      } else if (p > box.max[axis]) {
        c[axis] = a[axis] - box.max[axis];
        k[axis] = d[axis];
      }
      sum_ck += c[axis] * k[axis];
      sum_kk += k[axis] * k[axis];
    }
    double t = sum_kk > 0.0 ? std::clamp(-sum_ck / sum_kk, t0, t1) : t0;
    double value = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const double e = c[axis] + k[axis] * t;
      value += e * e;
    }
    best = std::min(best, value);
  }
  // The ends themselves (pieces of zero length when a cut is at 0 or 1).
  for (const Vec3d p : {a, b}) best = std::min(best, distance_squared(p, box));
  return best;
}

Overlap overlap(const OrientedBox& box, const Aabb& cube) {
  const Vec3d half{0.5 * (cube.max.x - cube.min.x), 0.5 * (cube.max.y - cube.min.y), 0.5 * (cube.max.z - cube.min.z)};
  const Vec3d centre = cube.min + half;
  const Vec3d between = box.center - centre;
  // Separating axis test: the cube's 3 axes, the box's 3, and their 9 cross products.
  auto separated = [&](Vec3d axis) {
    const double cube_radius = half.x * std::fabs(axis.x) + half.y * std::fabs(axis.y) + half.z * std::fabs(axis.z);
    double box_radius = 0.0;
    for (int i = 0; i < 3; ++i) box_radius += box.half_extents[i] * std::fabs(box.axes[i].dot(axis));
    return std::fabs(between.dot(axis)) > cube_radius + box_radius;
  };
  const std::array<Vec3d, 3> world{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (const Vec3d& axis : world) {
    if (separated(axis)) return Overlap::outside;
  }
  for (const Vec3d& axis : box.axes) {
    if (separated(axis)) return Overlap::outside;
  }
  for (const Vec3d& w : world) {
    for (const Vec3d& b : box.axes) {
      const Vec3d axis = cross(w, b);
      // Parallel edges give no axis; the face axes above cover that case.
      if (axis.dot(axis) > 1e-12 && separated(axis)) return Overlap::outside;
    }
  }
  for (const Vec3d& c : corners(cube)) {
    const Vec3d d = c - box.center;
    for (int i = 0; i < 3; ++i) {
      if (std::fabs(d.dot(box.axes[i])) > box.half_extents[i]) return Overlap::partly;
    }
  }
  return Overlap::inside;
}

FrustumGeometry::FrustumGeometry(const Frustum& f_in)
    : frustum(f_in), f(f_in.forward()), l(f_in.left()), u(f_in.up()) {
  cos_half_h = std::cos(frustum.hfov / 2);
  sin_half_h = std::sin(frustum.hfov / 2);
  cos_half_v = std::cos(frustum.vfov / 2);
  sin_half_v = std::sin(frustum.vfov / 2);
  // |atan2(d.l, d.f)| <= h/2 with d.f > 0  <=>  d.(f sin - l cos) >= 0 and d.(f sin + l cos) >= 0.
  side = {f * sin_half_h - l * cos_half_h, f * sin_half_h + l * cos_half_h, f * sin_half_v - u * cos_half_v,
          f * sin_half_v + u * cos_half_v};
}

bool FrustumGeometry::contains(Vec3d point) const {
  const Vec3d d = point - frustum.origin;
  const double along = d.dot(f);
  if (!(along > 0.0)) return false;
  if (std::fabs(std::atan2(d.dot(l), along)) > frustum.hfov / 2) return false;
  if (std::fabs(std::atan2(d.dot(u), along)) > frustum.vfov / 2) return false;
  const double distance = d.norm();
  return distance >= frustum.min_range && distance <= frustum.max_range;
}

bool FrustumGeometry::contains_quickly(Vec3d point) const {
  const Vec3d d = point - frustum.origin;
  const double distance2 = d.dot(d);
  // The margins of overlap() for a single point.
  const double margin = 1e-9 * (std::sqrt(distance2) + 1.0);
  const double range_margin = 1e-9 * (frustum.max_range + 1.0);
  bool sure = true;
  for (const Vec3d& normal : side) {
    const double s = normal.dot(d);
    if (s < -margin) return false;
    if (s <= margin) sure = false;
  }
  const double low = frustum.min_range + range_margin;
  const double high = frustum.max_range - range_margin;
  if (sure && distance2 >= low * low && distance2 <= high * high) return true;
  // Surely beyond the range or before min_range: no atan2 (the centres just
  // past max_range went to contains(), 2.6% of a 20 cm gain query).
  const double beyond = frustum.max_range + range_margin;
  const double before = frustum.min_range - range_margin;
  if (distance2 > beyond * beyond || (before > 0.0 && distance2 < before * before)) return false;
  return contains(point);
}

int FrustumGeometry::count_grid_points(const double* xs, const double* ys, const double* zs, int n) const {
  constexpr int kMax = 8;
  const Vec3d o = frustum.origin;
  // The plane and range terms of each coordinate, multiplied as
  // contains_quickly() multiplies them (so the sums below are its values to
  // the bit: d.dot(normal) is x * nx + y * ny + z * nz, left to right).
  double dx[kMax], dy[kMax], dz[kMax];
  double sx[4][kMax], sy[4][kMax], sz[4][kMax];
  double farthest2 = 0.0;
  for (int i = 0; i < n; ++i) {
    dx[i] = xs[i] - o.x;
    dy[i] = ys[i] - o.y;
    dz[i] = zs[i] - o.z;
    for (int plane = 0; plane < 4; ++plane) {
      sx[plane][i] = dx[i] * side[std::size_t(plane)].x;
      sy[plane][i] = dy[i] * side[std::size_t(plane)].y;
      sz[plane][i] = dz[i] * side[std::size_t(plane)].z;
    }
  }
  for (const double* d : {dx, dy, dz}) farthest2 += std::max(d[0] * d[0], d[n - 1] * d[n - 1]);
  // One margin for the block, from its farthest point: at least each
  // point's own (a larger margin only sends more points to contains()).
  const double margin = 1e-9 * (std::sqrt(farthest2) * (1.0 + 1e-12) + 1.0);
  const double range_margin = 1e-9 * (frustum.max_range + 1.0);
  const double low = frustum.min_range + range_margin;
  const double high = frustum.max_range - range_margin;
  const double beyond = frustum.max_range + range_margin;
  const double before = frustum.min_range - range_margin;
  // Constraints the whole block surely meets are left out of the loop
  // (most boundary blocks cross one plane or the range): rounded addition
  // is monotone, so a point's sum is at least the sum of the least terms,
  // added in the same order, and at most that of the greatest.
  auto least = [n](const double* v) { return *std::min_element(v, v + n); };
  auto greatest = [n](const double* v) { return *std::max_element(v, v + n); };
  std::array<int, 4> planes{};
  int active = 0;
  for (int plane = 0; plane < 4; ++plane) {
    if (least(sx[plane]) + least(sy[plane]) + least(sz[plane]) > margin) continue;  // surely inside this one
    if (greatest(sx[plane]) + greatest(sy[plane]) + greatest(sz[plane]) < -margin) return 0;
    planes[std::size_t(active++)] = plane;
  }
  double square_x[kMax], square_y[kMax], square_z[kMax];
  for (int i = 0; i < n; ++i) {
    square_x[i] = dx[i] * dx[i];
    square_y[i] = dy[i] * dy[i];
    square_z[i] = dz[i] * dz[i];
  }
  const bool range_sure = farthest2 <= high * high &&
                          least(square_x) + least(square_y) + least(square_z) >= low * low;
  if (range_sure && active == 0) return n * n * n;
  int count = 0;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        bool sure = range_sure;
        if (!range_sure) {
          const double distance2 = square_x[i] + square_y[j] + square_z[k];
          if (distance2 > beyond * beyond || (before > 0.0 && distance2 < before * before)) continue;
          sure = distance2 >= low * low && distance2 <= high * high;
        }
        bool out = false;
        for (int a = 0; a < active; ++a) {
          const int plane = planes[std::size_t(a)];
          const double value = sx[plane][i] + sy[plane][j] + sz[plane][k];
          out |= value < -margin;
          sure &= value > margin;
        }
        if (out) continue;
        if (sure || contains({xs[i], ys[j], zs[k]})) ++count;
      }
    }
  }
  return count;
}


}  // namespace umbra::detail
