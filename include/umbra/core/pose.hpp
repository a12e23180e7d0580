// Pose: a rigid (or, for readers of other tools' files, affine) 3D
// transform, world = R p + t, kept as a 3x4 matrix in double and applied to
// float points with one rounding per coordinate.
//
// It places a sensor in the map: a depth camera's pose is the transform of
// its optical frame (x right, y down, z forward) into the map frame, as TUM
// RGB-D's ground truth and ROS's camera frames give it.
#pragma once

#include <array>

#include "umbra/core/vec3.hpp"

namespace umbra {

struct Pose {
  /// Row-major [R | t]; identity by default.
  std::array<std::array<double, 4>, 3> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};

  /// From a translation and a quaternion (w, x, y, z), normalised here.
  /// Throws std::invalid_argument for a non-finite value or a zero quaternion.
  static Pose from_translation_quaternion(double tx, double ty, double tz, double qw, double qx, double qy,
                                          double qz);

  [[nodiscard]] Vec3f translation() const {
    return {static_cast<float>(m[0][3]), static_cast<float>(m[1][3]), static_cast<float>(m[2][3])};
  }
  [[nodiscard]] Vec3d translation_d() const { return {m[0][3], m[1][3], m[2][3]}; }
  [[nodiscard]] bool is_identity() const;
  /// Determinant of the 3x3 part: 1 for a rotation, 0 when it flattens space.
  [[nodiscard]] double determinant() const;
  /// Whether every entry is finite and the 3x3 part is a rotation (orthonormal,
  /// determinant +1) to within `tolerance`.
  [[nodiscard]] bool is_rigid(double tolerance = 1e-6) const;

  [[nodiscard]] Vec3f apply(Vec3f p) const { return apply(double(p.x), double(p.y), double(p.z)); }
  /// The same, for a point given in double.
  [[nodiscard]] Vec3f apply(double x, double y, double z) const {
    return {static_cast<float>(m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3]),
            static_cast<float>(m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3]),
            static_cast<float>(m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3])};
  }

  /// this * other (apply `other` first).
  [[nodiscard]] Pose operator*(const Pose& other) const;
};

}  // namespace umbra
