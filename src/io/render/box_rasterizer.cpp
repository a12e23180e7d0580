#include "box_rasterizer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace umbra::detail {

namespace {

// Slack of the inside test, in face coordinates (0..1): a pixel centre on a
// shared edge belongs to both faces despite rounding.
constexpr double kEdgeSlack = 1e-9;

Vec3d unit(Vec3d v) { return v / v.norm(); }

std::uint8_t scaled(std::uint8_t channel, double factor) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(double(channel) * factor, 0.0, 255.0)));
}

}  // namespace

BoxRasterizer::BoxRasterizer(const RenderCamera& camera, Image& image)
    : camera_(camera),
      light_(unit(camera.toward + 0.8 * camera.up - 0.4 * camera.right)),
      image_(image),
      depth_(std::size_t(image.width) * std::size_t(image.height), -std::numeric_limits<float>::infinity()) {}

double BoxRasterizer::shade(Vec3d normal) const { return 0.5 + 0.5 * std::max(0.0, normal.dot(light_)); }

template <typename Face>
void BoxRasterizer::for_each_facing_face(Vec3d min, Vec3d max, Face&& face) const {
  const Vec3d size = max - min;
  for (int axis = 0; axis < 3; ++axis) {
    // The face of this axis that looks toward the viewer, if one does.
    const double facing = camera_.toward[std::size_t(axis)];
    if (std::abs(facing) < 1e-12) continue;  // both faces edge-on
    Vec3d normal{};
    normal[std::size_t(axis)] = facing > 0 ? 1.0 : -1.0;
    Vec3d corner = min;
    if (facing > 0) corner[std::size_t(axis)] = max[std::size_t(axis)];
    Vec3d edge_a{};
    Vec3d edge_b{};
    const auto a = std::size_t((axis + 1) % 3);
    const auto b = std::size_t((axis + 2) % 3);
    edge_a[a] = size[a];
    edge_b[b] = size[b];
    face(corner, edge_a, edge_b, normal);
  }
}

void BoxRasterizer::draw_box(Vec3d min, Vec3d max, Rgb color) {
  for_each_facing_face(min, max, [&](Vec3d corner, Vec3d edge_a, Vec3d edge_b, Vec3d normal) {
    const double factor = shade(normal);
    draw_face(corner, edge_a, edge_b, {scaled(color.r, factor), scaled(color.g, factor), scaled(color.b, factor)},
              true);
  });
}

void BoxRasterizer::paint_silhouette(Vec3d min, Vec3d max, Rgb color) {
  for_each_facing_face(min, max, [&](Vec3d corner, Vec3d edge_a, Vec3d edge_b, Vec3d) {
    draw_face(corner, edge_a, edge_b, color, false);
  });
}

void BoxRasterizer::draw_face(Vec3d corner, Vec3d edge_a, Vec3d edge_b, Rgb color, bool depth_tested) {
  const double mpp = camera_.metres_per_pixel;
  const auto [cx, cy] = camera_.pixel(corner);
  // The edges on screen (rows grow downwards).
  const double ax = edge_a.dot(camera_.right) / mpp;
  const double ay = -edge_a.dot(camera_.up) / mpp;
  const double bx = edge_b.dot(camera_.right) / mpp;
  const double by = -edge_b.dot(camera_.up) / mpp;
  const double det = ax * by - ay * bx;
  if (std::abs(det) < 1e-12) return;  // seen edge-on
  const double depth0 = corner.dot(camera_.toward);
  const double depth_a = edge_a.dot(camera_.toward);
  const double depth_b = edge_b.dot(camera_.toward);

  const double min_x = std::min({cx, cx + ax, cx + bx, cx + ax + bx});
  const double max_x = std::max({cx, cx + ax, cx + bx, cx + ax + bx});
  const double min_y = std::min({cy, cy + ay, cy + by, cy + ay + by});
  const double max_y = std::max({cy, cy + ay, cy + by, cy + ay + by});
  // Pixels whose centre (column + 0.5, row + 0.5) can lie in the face.
  const auto first_column = static_cast<int>(std::max(0.0, std::ceil(min_x - 0.5 - kEdgeSlack)));
  const auto last_column = static_cast<int>(std::min(double(image_.width - 1), std::floor(max_x - 0.5 + kEdgeSlack)));
  const auto first_row = static_cast<int>(std::max(0.0, std::ceil(min_y - 0.5 - kEdgeSlack)));
  const auto last_row = static_cast<int>(std::min(double(image_.height - 1), std::floor(max_y - 0.5 + kEdgeSlack)));

  for (int row = first_row; row <= last_row; ++row) {
    const double qy = row + 0.5 - cy;
    for (int column = first_column; column <= last_column; ++column) {
      const double qx = column + 0.5 - cx;
      // q = s a + t b: the pixel centre in face coordinates.
      const double s = (qx * by - qy * bx) / det;
      const double t = (ax * qy - ay * qx) / det;
      if (s < -kEdgeSlack || s > 1 + kEdgeSlack || t < -kEdgeSlack || t > 1 + kEdgeSlack) continue;
      const std::size_t pixel = std::size_t(row) * std::size_t(image_.width) + std::size_t(column);
      if (depth_tested) {
        const auto depth = static_cast<float>(depth0 + s * depth_a + t * depth_b);
        if (!(depth > depth_[pixel])) continue;
        depth_[pixel] = depth;
      }
      std::uint8_t* out = image_.rgb.data() + 3 * pixel;
      out[0] = color.r;
      out[1] = color.g;
      out[2] = color.b;
    }
  }
}

}  // namespace umbra::detail
