#include "umbra/query/shapes.hpp"

#include "query/geometry.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace umbra {
namespace {

std::string text(Vec3d v) {
  return "(" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ")";
}

void require_finite(Vec3d v, const char* what) {
  if (!v.is_finite()) throw std::invalid_argument(std::string(what) + " must be finite, got " + text(v));
}

void require_radius(double radius, const char* shape) {
  if (!(std::isfinite(radius) && radius >= 0.0)) {
    throw std::invalid_argument(std::string(shape) + " radius must be finite and >= 0, got " + std::to_string(radius));
  }
}

Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

}  // namespace

void Sphere::validate() const {
  require_finite(center, "sphere centre");
  require_radius(radius, "sphere");
}

void Segment::validate() const {
  require_finite(from, "segment start");
  require_finite(to, "segment end");
}

void Capsule::validate() const {
  require_finite(a, "capsule start");
  require_finite(b, "capsule end");
  require_radius(radius, "capsule");
}

OrientedBox OrientedBox::from_yaw_pitch_roll(Vec3d center, Vec3d half_extents, double yaw, double pitch,
                                             double roll) {
  const Vec3d f{std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
  const Vec3d l{-std::sin(yaw), std::cos(yaw), 0.0};
  const Vec3d u = cross(f, l);
  const double c = std::cos(roll);
  const double s = std::sin(roll);
  OrientedBox box;
  box.center = center;
  box.half_extents = half_extents;
  box.axes = {f, l * c + u * s, u * c - l * s};
  return box;
}

OrientedBox OrientedBox::from_quaternion(Vec3d center, Vec3d half_extents, double w, double x, double y, double z) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!(std::isfinite(n) && n > 0.0)) throw std::invalid_argument("oriented box: the quaternion is zero or not finite");
  w /= n;
  x /= n;
  y /= n;
  z /= n;
  OrientedBox box;
  box.center = center;
  box.half_extents = half_extents;
  // The columns of the rotation matrix.
  box.axes = {Vec3d{1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)},
              Vec3d{2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)},
              Vec3d{2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}};
  return box;
}

void OrientedBox::validate() const {
  require_finite(center, "oriented box centre");
  require_finite(half_extents, "oriented box half extents");
  if (half_extents.x < 0 || half_extents.y < 0 || half_extents.z < 0) {
    throw std::invalid_argument("oriented box half extents must be >= 0, got " + text(half_extents));
  }
  for (int i = 0; i < 3; ++i) {
    require_finite(axes[i], "oriented box axis");
    for (int j = i; j < 3; ++j) {
      const double expected = i == j ? 1.0 : 0.0;
      if (std::fabs(axes[i].dot(axes[j]) - expected) > 1e-6) {
        throw std::invalid_argument("oriented box axes must be orthonormal; axes " + std::to_string(i) + " and " +
                                    std::to_string(j) + " have dot product " + std::to_string(axes[i].dot(axes[j])));
      }
    }
  }
}

Frustum Frustum::from_degrees(Vec3d origin, double yaw_deg, double pitch_deg, double hfov_deg, double vfov_deg,
                              double min_range, double max_range) {
  constexpr double kRadians = std::numbers::pi / 180.0;
  return {origin, yaw_deg * kRadians, pitch_deg * kRadians, hfov_deg * kRadians, vfov_deg * kRadians, min_range,
          max_range};
}

Vec3d Frustum::forward() const {
  return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
}

Vec3d Frustum::left() const { return {-std::sin(yaw), std::cos(yaw), 0.0}; }

Vec3d Frustum::up() const { return cross(forward(), left()); }

bool Frustum::contains(Vec3d point) const { return detail::FrustumGeometry(*this).contains(point); }

void Frustum::validate() const {
  require_finite(origin, "frustum origin");
  if (!std::isfinite(yaw) || !std::isfinite(pitch)) {
    throw std::invalid_argument("frustum yaw and pitch must be finite, got " + std::to_string(yaw) + ", " +
                                std::to_string(pitch));
  }
  // Below pi: the field of view is a pyramid in front of the sensor (planes
  // through the origin bound it, which the traversal relies on).
  if (!(hfov > 0.0 && hfov < std::numbers::pi) || !(vfov > 0.0 && vfov < std::numbers::pi)) {
    throw std::invalid_argument("frustum fields of view must lie in (0, 180) degrees, got hfov " +
                                std::to_string(hfov * 180.0 / std::numbers::pi) + ", vfov " +
                                std::to_string(vfov * 180.0 / std::numbers::pi));
  }
  if (!(std::isfinite(min_range) && min_range >= 0.0 && std::isfinite(max_range) && max_range > min_range)) {
    throw std::invalid_argument("frustum ranges must satisfy 0 <= min_range < max_range (finite), got " +
                                std::to_string(min_range) + ", " + std::to_string(max_range));
  }
}

}  // namespace umbra
