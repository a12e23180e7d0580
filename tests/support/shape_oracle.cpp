#include "support/shape_oracle.hpp"

#include <algorithm>
#include <vector>

namespace umbra::test {
namespace {

double point_segment_distance(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d d = b - a;
  const double t = d.dot(d) > 0 ? std::clamp((p - a).dot(d) / d.dot(d), 0.0, 1.0) : 0.0;
  return (p - (a + d * t)).norm();
}

}  // namespace

double clamp_distance_squared(Vec3d p, const Cube& c) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max({c.min[a] - p[a], 0.0, p[a] - c.max[a]});
    sum += d * d;
  }
  return sum;
}

bool meets(const Aabb& box, const Cube& c) {
  for (int a = 0; a < 3; ++a) {
    if (c.max[a] < box.min[a] || c.min[a] > box.max[a]) return false;
  }
  return true;
}

bool meets(const Sphere& s, const Cube& c) { return clamp_distance_squared(s.center, c) <= s.radius * s.radius; }

bool meets(const Capsule& capsule, const Cube& c) {
  // Quick answers from the cube's centre, then the minimum by ternary search
  // (the squared distance along the segment is convex).
  const Vec3d centre = (c.min + c.max) * 0.5;
  const double half_diagonal = (c.max - c.min).norm() * 0.5;
  const double centre_distance = point_segment_distance(centre, capsule.a, capsule.b);
  if (centre_distance > capsule.radius + half_diagonal) return false;
  if (centre_distance <= capsule.radius) return true;
  auto f = [&](double t) { return clamp_distance_squared(capsule.a + (capsule.b - capsule.a) * t, c); };
  double lo = 0.0;
  double hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double m1 = lo + (hi - lo) / 3;
    const double m2 = hi - (hi - lo) / 3;
    if (f(m1) < f(m2)) {
      hi = m2;
    } else {
      lo = m1;
    }
  }
  return std::min({f(lo), f(0.0), f(1.0)}) <= capsule.radius * capsule.radius;
}

bool meets(const OrientedBox& box, const Cube& c) {
  // Separating axes, by projecting all sixteen corners on each candidate axis.
  std::vector<Vec3d> cube_corners;
  std::vector<Vec3d> box_corners;
  for (unsigned i = 0; i < 8; ++i) {
    cube_corners.push_back({(i & 1) ? c.max.x : c.min.x, (i & 2) ? c.max.y : c.min.y, (i & 4) ? c.max.z : c.min.z});
    Vec3d p = box.center;
    for (int a = 0; a < 3; ++a) p = p + box.axes[a] * (((i >> a) & 1) ? box.half_extents[a] : -box.half_extents[a]);
    box_corners.push_back(p);
  }
  std::vector<Vec3d> axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, box.axes[0], box.axes[1], box.axes[2]};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3d a = axes[i];
      const Vec3d b = box.axes[j];
      const Vec3d x{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
      if (x.dot(x) > 1e-12) axes.push_back(x);
    }
  }
  for (const Vec3d& axis : axes) {
    double lo1 = 1e300;
    double hi1 = -1e300;
    double lo2 = 1e300;
    double hi2 = -1e300;
    for (const Vec3d& p : cube_corners) {
      lo1 = std::min(lo1, p.dot(axis));
      hi1 = std::max(hi1, p.dot(axis));
    }
    for (const Vec3d& p : box_corners) {
      lo2 = std::min(lo2, p.dot(axis));
      hi2 = std::max(hi2, p.dot(axis));
    }
    if (hi1 < lo2 || hi2 < lo1) return false;
  }
  return true;
}

}  // namespace umbra::test
