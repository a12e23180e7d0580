#include "umbra/core/pose.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>

namespace umbra {

Pose Pose::from_translation_quaternion(double tx, double ty, double tz, double qw, double qx, double qy, double qz) {
  for (const double value : {tx, ty, tz, qw, qx, qy, qz}) {
    if (!std::isfinite(value)) throw std::invalid_argument("the pose has a non-finite value");
  }
  const double largest = std::max({std::abs(qw), std::abs(qx), std::abs(qy), std::abs(qz)});
  if (largest == 0.0) throw std::invalid_argument("the rotation quaternion is (0, 0, 0, 0), which is no rotation");
  double w = qw / largest;
  double x = qx / largest;
  double y = qy / largest;
  double z = qz / largest;
  const double norm = std::sqrt(w * w + x * x + y * y + z * z);
  w /= norm;
  x /= norm;
  y /= norm;
  z /= norm;
  Pose pose;
  pose.m = {{{1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y), tx},
             {2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x), ty},
             {2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y), tz}}};
  return pose;
}

bool Pose::is_identity() const {
  for (std::size_t row = 0; row < 3; ++row) {
    for (std::size_t column = 0; column < 4; ++column) {
      if (m[row][column] != (row == column ? 1.0 : 0.0)) return false;
    }
  }
  return true;
}

double Pose::determinant() const {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

bool Pose::is_rigid(double tolerance) const {
  for (const auto& row : m) {
    for (const double value : row) {
      if (!std::isfinite(value)) return false;
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t b = 0; b < 3; ++b) {
      double dot = 0.0;
      for (std::size_t k = 0; k < 3; ++k) dot += m[k][a] * m[k][b];
      if (std::abs(dot - (a == b ? 1.0 : 0.0)) > tolerance) return false;
    }
  }
  return std::abs(determinant() - 1.0) <= tolerance;
}

Pose Pose::operator*(const Pose& other) const {
  Pose product;
  for (std::size_t row = 0; row < 3; ++row) {
    for (std::size_t column = 0; column < 4; ++column) {
      double sum = column == 3 ? m[row][3] : 0.0;
      for (std::size_t k = 0; k < 3; ++k) sum += m[row][k] * other.m[k][column];
      product.m[row][column] = sum;
    }
  }
  return product;
}

}  // namespace umbra
