// Aabb: an axis-aligned box in metres, e.g. the part of the world a map keeps.
#pragma once

#include <optional>
#include <string>

#include "umbra/core/vec3.hpp"

namespace umbra {

struct Aabb {
  Vec3d min;
  Vec3d max;

  /// Throws std::invalid_argument unless min <= max on every axis and all finite.
  void validate() const;
  [[nodiscard]] bool contains(Vec3d p) const {
    return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z && p.z <= max.z;
  }
  /// The part [t0, t1] of the segment from + t (to - from), t in [0, 1],
  /// that lies in the box (slab test), or nothing.
  [[nodiscard]] std::optional<std::pair<double, double>> clip(Vec3d from, Vec3d to) const;
  friend bool operator==(const Aabb&, const Aabb&) = default;
};

}  // namespace umbra
