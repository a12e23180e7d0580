#include "umbra/map/depth_image.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "integrate/image_points.hpp"

namespace umbra {

namespace {

void check_size(std::size_t pixels, int width, int height) {
  if (width < 1 || height < 1) {
    throw std::invalid_argument("a depth image needs at least 1 x 1 pixels, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (pixels != std::size_t(width) * std::size_t(height)) {
    throw std::invalid_argument("a depth image of " + std::to_string(width) + " x " + std::to_string(height) +
                                " pixels needs " + std::to_string(std::size_t(width) * std::size_t(height)) +
                                " depths, got " + std::to_string(pixels));
  }
}

}  // namespace

void PinholeCamera::validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(fx) || !positive(fy) || !std::isfinite(cx) || !std::isfinite(cy)) {
    throw std::invalid_argument("PinholeCamera: fx and fy must be finite and > 0, cx and cy finite; got fx " +
                                std::to_string(fx) + ", fy " + std::to_string(fy) + ", cx " + std::to_string(cx) +
                                ", cy " + std::to_string(cy));
  }
}

DepthImage DepthImage::metres(std::span<const float> depth, int width, int height) {
  check_size(depth.size(), width, height);
  DepthImage image;
  image.width_ = width;
  image.height_ = height;
  image.metres_ = depth;
  return image;
}

DepthImage DepthImage::raw(std::span<const std::uint16_t> depth, int width, int height, double units_per_metre) {
  check_size(depth.size(), width, height);
  if (!(std::isfinite(units_per_metre) && units_per_metre > 0.0)) {
    throw std::invalid_argument("a raw depth image needs finite units_per_metre > 0, got " +
                                std::to_string(units_per_metre));
  }
  DepthImage image;
  image.width_ = width;
  image.height_ = height;
  image.raw_ = depth;
  image.inverse_scale_ = 1.0 / units_per_metre;
  return image;
}

void back_project(const DepthImage& depth, const PinholeCamera& camera, const Pose& pose, std::vector<Vec3f>& points,
                  std::vector<std::uint32_t>* pixels) {
  camera.validate();
  // Sized first (the buffers are the caller's, kept from frame to frame):
  // no growth while the rows are projected.
  const std::size_t count = count_readings(depth, 0, depth.height());
  points.resize(count);
  if (pixels != nullptr) pixels->resize(count);
  back_project_rows(depth, camera, pose, 0, depth.height(), points.data(), pixels != nullptr ? pixels->data() : nullptr);
}

}  // namespace umbra
