#include "umbra/core/aabb.hpp"

#include <cmath>
#include <stdexcept>

namespace umbra {

void Aabb::validate() const {
  for (int axis = 0; axis < 3; ++axis) {
    if (!std::isfinite(min[axis]) || !std::isfinite(max[axis]) || min[axis] > max[axis]) {
      throw std::invalid_argument("bounding box: axis " + std::to_string(axis) + " must have finite min <= max, got [" +
                                  std::to_string(min[axis]) + ", " + std::to_string(max[axis]) + "]");
    }
  }
}

std::optional<std::pair<double, double>> Aabb::clip(Vec3d from, Vec3d to) const {
  double t0 = 0.0;
  double t1 = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = to[axis] - from[axis];
    if (d == 0.0) {
      if (from[axis] < min[axis] || from[axis] > max[axis]) return std::nullopt;
      continue;
    }
    double a = (min[axis] - from[axis]) / d;
    double b = (max[axis] - from[axis]) / d;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return std::nullopt;
  }
  return std::pair{t0, t1};
}

}  // namespace umbra
