#include "umbra/integrate/depth_image.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

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
  points.clear();
  if (pixels != nullptr) pixels->clear();
  const int width = depth.width();
  const std::size_t count = depth.pixel_count();
  // Room for every pixel first (the buffers are the caller's, kept from
  // frame to frame): no growth inside the loop.
  points.reserve(count);
  if (pixels != nullptr) pixels->reserve(count);
  std::vector<double> column_factor(static_cast<std::size_t>(width));
  for (int u = 0; u < width; ++u) column_factor[static_cast<std::size_t>(u)] = (u - camera.cx) / camera.fx;
  // One loop per kind of image, so that the pixel loop does not ask which.
  auto project = [&](auto&& depth_of) {
    std::size_t index = 0;
    for (int v = 0; v < depth.height(); ++v) {
      const double row_factor = (v - camera.cy) / camera.fy;
      for (int u = 0; u < width; ++u, ++index) {
        const double z = depth_of(index);
        if (z == 0.0) continue;
        points.push_back(pose.apply(column_factor[static_cast<std::size_t>(u)] * z, row_factor * z, z));
        if (pixels != nullptr) pixels->push_back(static_cast<std::uint32_t>(index));
      }
    }
  };
  if (depth.is_raw()) {
    const std::span<const std::uint16_t> raw = depth.raw_depths();
    const double scale = depth.metres_per_unit();
    project([&](std::size_t i) { return raw[i] * scale; });
  } else {
    project([&](std::size_t i) { return depth.depth(i); });
  }
}

}  // namespace umbra
