// Depth images: what a depth camera gives, for OccupancyMap::insert_depth_image.
//
// A depth image holds, per pixel, the depth z of the surface seen there: the
// distance along the camera's optical axis, not along the pixel's ray. Pixel
// (u, v) (u to the right, v down, both from 0 at the top-left pixel's centre)
// with depth z lies at camera point (x, y, z) = ((u - cx) z / fx, (v - cy) z
// / fy, z) in the optical frame (x right, y down, z forward), and at
// pose.apply(x, y, z) in the map. A pixel without a reading holds 0 (16-bit
// images) or 0, a negative value, NaN or infinity (float images).
//
//   std::vector<std::uint16_t> raw = ...;                      // 640 x 480, 1/5000 m units
//   map.insert_depth_image(umbra::DepthImage::raw(raw, 640, 480, 5000.0),
//                          umbra::PinholeCamera{580.8, 581.8, 308.8, 253.0}, camera_to_world);
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// Pinhole intrinsics in pixels.
struct PinholeCamera {
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;

  /// Throws std::invalid_argument unless fx, fy are finite and > 0 and cx, cy finite.
  void validate() const;
};

/// A read-only view of a depth image (16-bit raw units or float metres), row
/// by row from the top, each row left to right. It does not own the pixels.
class DepthImage {
 public:
  /// Depths in metres.
  static DepthImage metres(std::span<const float> depth, int width, int height);
  /// Raw 16-bit depths, `units_per_metre` per metre (TUM and Kinect: 5000 or
  /// 1000); 0 means no reading.
  static DepthImage raw(std::span<const std::uint16_t> depth, int width, int height, double units_per_metre);

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] std::size_t pixel_count() const { return std::size_t(width_) * std::size_t(height_); }
  /// Whether the image holds raw 16-bit depths (else float metres).
  [[nodiscard]] bool is_raw() const { return !raw_.empty(); }
  [[nodiscard]] std::span<const std::uint16_t> raw_depths() const { return raw_; }
  [[nodiscard]] std::span<const float> metre_depths() const { return metres_; }
  /// Metres per raw unit (raw images).
  [[nodiscard]] double metres_per_unit() const { return inverse_scale_; }
  /// Depth in metres of pixel `index` (v * width + u); 0 when it has no reading.
  [[nodiscard]] double depth(std::size_t index) const {
    if (!raw_.empty()) return raw_[index] * inverse_scale_;
    const float z = metres_[index];
    return z > 0.0f && z < std::numeric_limits<float>::infinity() ? double(z) : 0.0;
  }

 private:
  DepthImage() = default;
  int width_ = 0;
  int height_ = 0;
  std::span<const float> metres_;
  std::span<const std::uint16_t> raw_;
  double inverse_scale_ = 0.0;  // metres per raw unit
};

/// The map points of the pixels with a reading, row by row (see the file
/// comment: z = depth, x = (u - cx) z / fx, y = (v - cy) z / fy, in double,
/// then pose.apply). `pixels`, when given, receives each point's pixel index.
/// Every reader of depth images and insert_depth_image use this one
/// function, so that a depth image and the point cloud made from it give the
/// same points.
void back_project(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose, std::vector<Vec3f>& points,
                  std::vector<std::uint32_t>* pixels = nullptr);

}  // namespace umbra
