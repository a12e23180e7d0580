// A plain 3-vector for points, origins and sizes.
//
// Point clouds use Vec3f (like OctoMap's point3d, so that ray casting rounds
// exactly as OctoMap does); geometry that users pass for queries uses Vec3d.
#pragma once

#include <cmath>
#include <cstddef>

namespace umbra {

template <typename T>
struct Vec3 {
  T x{};
  T y{};
  T z{};

  constexpr T& operator[](std::size_t axis) { return axis == 0 ? x : (axis == 1 ? y : z); }
  constexpr const T& operator[](std::size_t axis) const {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }

  friend constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend constexpr Vec3 operator*(Vec3 a, T s) { return {a.x * s, a.y * s, a.z * s}; }
  friend constexpr Vec3 operator*(T s, Vec3 a) { return a * s; }
  friend constexpr Vec3 operator/(Vec3 a, T s) { return {a.x / s, a.y / s, a.z / s}; }
  friend constexpr bool operator==(Vec3 a, Vec3 b) = default;

  template <typename U>
  constexpr explicit operator Vec3<U>() const {
    return {static_cast<U>(x), static_cast<U>(y), static_cast<U>(z)};
  }

  [[nodiscard]] constexpr T dot(Vec3 b) const { return x * b.x + y * b.y + z * b.z; }
  [[nodiscard]] T norm() const { return std::sqrt(dot(*this)); }
  [[nodiscard]] bool is_finite() const {
    return std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
  }
};

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

}  // namespace umbra
