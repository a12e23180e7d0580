// Tests of render_map (views and slices of a map). Three kinds of check:
//  - properties predicted from the documented camera (map_render.hpp) with
//    the test's own arithmetic: where a voxel lands, which box hides which,
//    what a slice through a known box shows;
//  - brute force: axis views and slices of the simulated demo building at
//    one pixel per voxel, pixel for pixel against per-voxel state() lookups;
//  - golden pictures (tests/io/golden/, see the RenderGolden tests below).
#include "umbra/io/map_render.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/io/topdown_image.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"
#include "support/demo_maps.hpp"

namespace umbra {
namespace {

constexpr double kResolution = 0.1;

std::string text(Rgb c) {
  return "(" + std::to_string(c.r) + ", " + std::to_string(c.g) + ", " + std::to_string(c.b) + ")";
}

/// Centre of the voxel with indices (i, j, k) counted from the map origin.
Vec3d voxel(int i, int j, int k) {
  return {(i + 0.5) * kResolution, (j + 0.5) * kResolution, (k + 0.5) * kResolution};
}

// The camera axes as map_render.hpp documents them, written out here.
struct Axes {
  Vec3d right;
  Vec3d up;
  Vec3d toward;
};

Axes documented_axes(RenderView view) {
  const double r2 = std::sqrt(2.0);
  const double r6 = std::sqrt(6.0);
  const double r3 = std::sqrt(3.0);
  switch (view) {
    case RenderView::top: return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    case RenderView::front: return {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}};
    case RenderView::side: return {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
    case RenderView::iso: break;
  }
  return {{1 / r2, -1 / r2, 0}, {1 / r6, 1 / r6, 2 / r6}, {-1 / r3, -1 / r3, 1 / r3}};
}

Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

/// The documented shading factor of a face with outward normal n.
double documented_shade(const Axes& axes, Vec3d normal) {
  Vec3d light = axes.toward + 0.8 * axes.up - 0.4 * axes.right;
  light = light / light.norm();
  return 0.5 + 0.5 * std::max(0.0, normal.dot(light));
}

Rgb shaded(Rgb c, double factor) {
  auto channel = [&](std::uint8_t v) { return static_cast<std::uint8_t>(std::lround(double(v) * factor)); };
  return {channel(c.r), channel(c.g), channel(c.b)};
}

/// The documented framing: content box projected, width given, centred.
struct PredictedFrame {
  double mpp = 0;
  double left = 0;
  double top = 0;
  int width = 0;
  int height = 0;
  [[nodiscard]] std::pair<int, int> pixel(const Axes& axes, Vec3d p) const {
    return {static_cast<int>(std::floor((p.dot(axes.right) - left) / mpp)),
            static_cast<int>(std::floor((top - p.dot(axes.up)) / mpp))};
  }
};

PredictedFrame predict_frame(const Axes& axes, Vec3d low, Vec3d high, int width, int margin) {
  double r0 = std::numeric_limits<double>::infinity();
  double r1 = -r0;
  double u0 = r0;
  double u1 = -r0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d p{(corner & 1) ? high.x : low.x, (corner & 2) ? high.y : low.y, (corner & 4) ? high.z : low.z};
    r0 = std::min(r0, p.dot(axes.right));
    r1 = std::max(r1, p.dot(axes.right));
    u0 = std::min(u0, p.dot(axes.up));
    u1 = std::max(u1, p.dot(axes.up));
  }
  PredictedFrame frame;
  frame.width = width;
  frame.mpp = (r1 - r0) / (width - 2 * margin);
  frame.height = static_cast<int>(std::ceil((u1 - u0) / frame.mpp - 1e-9)) + 2 * margin;
  frame.left = (r0 + r1) / 2 - width * frame.mpp / 2;
  frame.top = (u0 + u1) / 2 + frame.height * frame.mpp / 2;
  return frame;
}

constexpr std::array<RenderView, 4> kViews{RenderView::top, RenderView::front, RenderView::side, RenderView::iso};

TEST(RenderCamera, AxesAreTheDocumentedRightHandedUnitVectors) {
  for (const RenderView view : kViews) {
    const RenderCamera camera = RenderCamera::axes_of(view);
    const Axes expected = documented_axes(view);
    for (std::size_t axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(camera.right[axis], expected.right[axis], 1e-12) << to_string(view);
      EXPECT_NEAR(camera.up[axis], expected.up[axis], 1e-12) << to_string(view);
      EXPECT_NEAR(camera.toward[axis], expected.toward[axis], 1e-12) << to_string(view);
      EXPECT_NEAR(cross(camera.right, camera.up)[axis], camera.toward[axis], 1e-12) << to_string(view);
    }
  }
  EXPECT_EQ(slice_view(0), RenderView::side);
  EXPECT_EQ(slice_view(1), RenderView::front);
  EXPECT_EQ(slice_view(2), RenderView::top);
}

TEST(MapRender, VoxelsLandOnThePredictedPixels) {
  OccupancyMap map(kResolution);
  const std::vector<Vec3d> centres{voxel(0, 0, 0), voxel(20, 10, 5), voxel(-10, 15, 10)};
  for (const Vec3d& c : centres) map.set_log_odds(c, 2.0f);
  const Vec3d low = voxel(-10, 0, 0) - Vec3d{0.05, 0.05, 0.05};
  const Vec3d high = voxel(20, 15, 10) + Vec3d{0.05, 0.05, 0.05};

  for (const RenderView view : kViews) {
    RenderOptions options;
    options.view = view;
    options.width = 400;  // a voxel is about 10 pixels across
    const MapPicture picture = render_map(map, options);
    const Axes axes = documented_axes(view);
    const PredictedFrame frame = predict_frame(axes, low, high, options.width, options.margin_pixels);
    ASSERT_EQ(picture.image.width, frame.width) << to_string(view);
    ASSERT_EQ(picture.image.height, frame.height) << to_string(view);
    EXPECT_NEAR(picture.camera.metres_per_pixel, frame.mpp, 1e-12);
    EXPECT_EQ(picture.nodes_drawn, 3u);

    // Each voxel's face toward the viewer that is most nearly facing it:
    // its centre lies well inside the face on the picture.
    std::size_t facing_axis = 0;
    for (std::size_t axis = 1; axis < 3; ++axis) {
      if (std::abs(axes.toward[axis]) > std::abs(axes.toward[facing_axis])) facing_axis = axis;
    }
    Vec3d normal{};
    normal[facing_axis] = axes.toward[facing_axis] > 0 ? 1.0 : -1.0;
    for (const Vec3d& c : centres) {
      // Height colors: the voxels' centres are at z 0.05, 0.55 and 1.05.
      const Rgb expected = shaded(height_ramp((c.z - 0.05) / 1.0), documented_shade(axes, normal));
      const Vec3d face_centre = c + normal * (0.5 * kResolution);
      const auto [column, row] = frame.pixel(axes, face_centre);
      EXPECT_EQ(picture.image.at(column, row), expected)
          << to_string(view) << " voxel at (" << c.x << ", " << c.y << ", " << c.z << ") pixel " << column << ", "
          << row << " is " << text(picture.image.at(column, row));
      const auto [x, y] = picture.camera.pixel(face_centre);
      EXPECT_EQ(static_cast<int>(std::floor(x)), column);
      EXPECT_EQ(static_cast<int>(std::floor(y)), row);
    }
    // Far from every voxel: background. The picture's corners and centre.
    EXPECT_EQ(picture.image.at(0, 0), options.background);
    EXPECT_EQ(picture.image.at(frame.width - 1, frame.height - 1), options.background);
    std::size_t drawn = 0;
    for (std::size_t i = 0; i < picture.image.rgb.size(); i += 3) {
      const Rgb p{picture.image.rgb[i], picture.image.rgb[i + 1], picture.image.rgb[i + 2]};
      drawn += p == options.background ? 0 : 1;
    }
    // Three voxels of about 10 x 10 pixels per face; in iso, three faces each.
    const double face_pixels = std::pow(kResolution / frame.mpp, 2);
    EXPECT_GT(double(drawn), 3 * 0.7 * face_pixels) << to_string(view);
    EXPECT_LT(double(drawn), 3 * 3.2 * face_pixels) << to_string(view);
  }
}

TEST(MapRender, NearerVoxelsHideFartherOnes) {
  OccupancyMap map(kResolution);
  // A column of two voxels (z 0 and z 10) and a row of two (y 0 and y 10).
  map.set_log_odds(voxel(0, 0, 0), 2.0f);
  map.set_log_odds(voxel(0, 0, 10), 2.0f);
  map.set_log_odds(voxel(10, 0, 5), 2.0f);
  map.set_log_odds(voxel(10, 10, 5), 2.0f);
  RenderOptions options;
  options.width = 200;
  options.view = RenderView::top;
  const MapPicture top = render_map(map, options);
  EXPECT_DOUBLE_EQ(top.ramp_low, voxel(0, 0, 0).z);
  EXPECT_DOUBLE_EQ(top.ramp_high, voxel(0, 0, 10).z);
  const Axes top_axes = documented_axes(RenderView::top);
  const double top_shade = documented_shade(top_axes, {0, 0, 1});
  auto at = [](const MapPicture& picture, Vec3d p) {
    const auto [x, y] = picture.camera.pixel(p);
    return picture.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
  };
  EXPECT_EQ(at(top, voxel(0, 0, 10)), shaded(height_ramp(1.0), top_shade));  // the upper voxel wins
  EXPECT_EQ(at(top, voxel(10, 0, 5)), shaded(height_ramp(0.5), top_shade));

  options.view = RenderView::front;  // looking north: y 0 is nearer than y 10
  const MapPicture front = render_map(map, options);
  const double front_shade = documented_shade(documented_axes(RenderView::front), {0, -1, 0});
  EXPECT_EQ(at(front, voxel(10, 0, 5)), shaded(height_ramp(0.5), front_shade));
  EXPECT_EQ(at(front, voxel(0, 0, 10)), shaded(height_ramp(1.0), front_shade));
  EXPECT_EQ(at(front, voxel(0, 0, 0)), shaded(height_ramp(0.0), front_shade));

  // A height window: only nodes whose cube meets z <= 0.45 (the voxel at k = 0).
  options.view = RenderView::top;
  options.max_z = 0.45;
  const MapPicture low = render_map(map, options);
  EXPECT_EQ(low.nodes_drawn, 1u);
  EXPECT_EQ(at(low, voxel(0, 0, 0)), shaded(height_ramp(0.0), top_shade));  // the lower voxel shows now
  options.max_z.reset();
  options.min_z = 0.5;  // meets the voxels at k = 5 (z 0.5..0.6) and k = 10
  EXPECT_EQ(render_map(map, options).nodes_drawn, 3u);
}

TEST(MapRender, CoarserDepthDrawsParentCubes) {
  OccupancyMap map(kResolution);
  map.set_log_odds(voxel(0, 0, 0), 2.0f);
  map.set_log_odds(voxel(8, 8, 8), 2.0f);
  RenderOptions options;
  options.view = RenderView::top;
  options.depth = 2;  // 0.4 m cubes
  options.margin_pixels = 0;
  options.width = 80;  // 0.8 m across (two depth-2 nodes apart by one): 100 pixels per metre
  const MapPicture picture = render_map(map, options);
  EXPECT_EQ(picture.nodes_drawn, 2u);
  EXPECT_EQ(picture.depth, 2);
  EXPECT_NEAR(picture.camera.metres_per_pixel, 1.2 / 80, 1e-12);  // nodes at x 0..0.4 and 0.8..1.2
  // A depth-2 node covers the whole 0.4 m square: 32 x 32 pixels of one color.
  std::size_t drawn = 0;
  for (std::size_t i = 0; i < picture.image.rgb.size(); i += 3) drawn += picture.image.rgb[i] != 255 ? 1 : 0;
  const double side = 0.4 / picture.camera.metres_per_pixel;
  EXPECT_NEAR(double(drawn), 2 * side * side, 4 * side + 4);
}

// --- slices ------------------------------------------------------------------------

/// A free box of voxels [0, 10) x [0, 6) x [0, 4), one occupied voxel in it.
OccupancyMap free_box_map() {
  OccupancyMap map(kResolution);
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 6; ++j) {
      for (int k = 0; k < 4; ++k) map.set_log_odds(voxel(i, j, k), -1.0f);
    }
  }
  map.set_log_odds(voxel(3, 2, 1), 2.0f);
  return map;
}

/// Brute force over every leaf of the map (depth 0): those whose extent along
/// the slice axis holds the slice's plane (the centre of its voxel layer) and
/// that overlap the picture's rectangle.
std::size_t leaves_in_slice(const OccupancyMap& map, const MapPicture& picture, int axis, double position) {
  const double plane = (std::floor(position / kResolution) + 0.5) * kResolution;
  const RenderCamera& camera = picture.camera;
  const double right_low = camera.left;
  const double right_high = camera.left + picture.image.width * camera.metres_per_pixel;
  const double up_low = camera.top - picture.image.height * camera.metres_per_pixel;
  const double up_high = camera.top;
  std::size_t count = 0;
  map.for_each_leaf([&](const Node& leaf) {
    const auto a = std::size_t(axis);
    if (!(leaf.min_corner()[a] < plane && plane < leaf.max_corner()[a])) return;
    const double r0 = std::min(leaf.min_corner().dot(camera.right), leaf.max_corner().dot(camera.right));
    const double r1 = std::max(leaf.min_corner().dot(camera.right), leaf.max_corner().dot(camera.right));
    const double u0 = std::min(leaf.min_corner().dot(camera.up), leaf.max_corner().dot(camera.up));
    const double u1 = std::max(leaf.min_corner().dot(camera.up), leaf.max_corner().dot(camera.up));
    // Overlap by more than rounding: a leaf whose edge is the picture's edge
    // (as when a pixel is a voxel) does not count.
    const double slack = 1e-7 * camera.metres_per_pixel;
    if (r1 > right_low + slack && r0 < right_high - slack && u1 > up_low + slack && u0 < up_high - slack) ++count;
  });
  return count;
}

TEST(MapRenderSlice, ThroughAKnownFreeBoxIsFreeInsideAndUnknownAround) {
  const OccupancyMap map = free_box_map();
  for (int axis = 0; axis < 3; ++axis) {
    for (const double position : {0.05, 0.15, 0.25, 0.38}) {
      RenderOptions options;
      options.slice = RenderSlice{axis, position};
      options.view = slice_view(axis);
      options.color = RenderColor::state;
      options.width = 120;
      const MapPicture picture = render_map(map, options);
      const Axes axes = documented_axes(options.view);
      // Which voxel layer the slice is, and whether it holds the occupied voxel.
      const int layer = static_cast<int>(std::floor(position / kResolution));
      const int occupied_layer = axis == 0 ? 3 : (axis == 1 ? 2 : 1);
      std::size_t free = 0;
      std::size_t unknown = 0;
      std::size_t occupied = 0;
      for (int row = 0; row < picture.image.height; ++row) {
        for (int column = 0; column < picture.image.width; ++column) {
          const double r = picture.camera.left + (column + 0.5) * picture.camera.metres_per_pixel;
          const double u = picture.camera.top - (row + 0.5) * picture.camera.metres_per_pixel;
          // The pixel centre in map coordinates on the slice plane.
          Vec3d p = axes.right * r + axes.up * u;
          p[std::size_t(axis)] = (layer + 0.5) * kResolution;
          const bool inside = p.x > 0 && p.x < 1.0 && p.y > 0 && p.y < 0.6 && p.z > 0 && p.z < 0.4;
          const bool on_obstacle = layer == occupied_layer && std::floor(p.x / kResolution) == 3 &&
                                   std::floor(p.y / kResolution) == 2 && std::floor(p.z / kResolution) == 1;
          const Rgb expected = on_obstacle ? options.occupied_color : (inside ? options.free_color : options.unknown_color);
          const Rgb got = picture.image.at(column, row);
          ASSERT_EQ(got, expected) << "axis " << axis << " at " << position << ", pixel " << column << ", " << row
                                   << " (" << p.x << ", " << p.y << ", " << p.z << ") is " << text(got);
          free += got == options.free_color ? 1 : 0;
          unknown += got == options.unknown_color ? 1 : 0;
          occupied += got == options.occupied_color ? 1 : 0;
        }
      }
      EXPECT_GT(free, 0u);
      EXPECT_GT(unknown, 0u);
      EXPECT_EQ(occupied > 0, layer == occupied_layer);
      EXPECT_EQ(picture.nodes_drawn, leaves_in_slice(map, picture, axis, position));
    }
  }
}

TEST(MapRenderSlice, AFrameLinesUpPicturesOfDifferentMaps) {
  // Two maps whose known space differs; framed by the same box, their slices
  // have the same camera and size, and each pixel still shows its map.
  const OccupancyMap small = free_box_map();
  OccupancyMap large = free_box_map();
  for (int i = 10; i < 20; ++i) large.set_log_odds(voxel(i, 0, 1), -1.0f);
  RenderOptions options;
  options.slice = RenderSlice{2, 0.15};
  options.view = slice_view(2);
  options.color = RenderColor::state;
  options.width = 160;
  options.frame = Aabb{{-0.5, -0.5, 0.0}, {2.5, 1.0, 0.4}};
  const MapPicture a = render_map(small, options);
  const MapPicture b = render_map(large, options);
  EXPECT_EQ(a.camera.left, b.camera.left);
  EXPECT_EQ(a.camera.top, b.camera.top);
  EXPECT_EQ(a.camera.metres_per_pixel, b.camera.metres_per_pixel);
  ASSERT_EQ(a.image.width, b.image.width);
  ASSERT_EQ(a.image.height, b.image.height);
  // The box is in the picture (without a frame the small map's picture ends near x = 1).
  EXPECT_LE(a.camera.left, -0.5);
  EXPECT_GE(a.camera.left + a.image.width * a.camera.metres_per_pixel, 2.5);
  EXPECT_GE(a.camera.top, 1.0);
  EXPECT_LE(a.camera.top - a.image.height * a.camera.metres_per_pixel, -0.5);
  std::size_t differ = 0;
  for (int row = 0; row < a.image.height; ++row) {
    for (int column = 0; column < a.image.width; ++column) {
      const double x = a.camera.left + (column + 0.5) * a.camera.metres_per_pixel;
      const double y = a.camera.top - (row + 0.5) * a.camera.metres_per_pixel;
      const bool extra = x > 1.0 && x < 2.0 && y > 0.0 && y < 0.1;  // only the large map knows it
      if (extra && (std::fmod(x, kResolution) < 0.01 || std::fmod(y, kResolution) < 0.01)) continue;  // edges
      EXPECT_EQ(a.image.at(column, row) != b.image.at(column, row), extra) << column << ", " << row;
      differ += a.image.at(column, row) != b.image.at(column, row) ? 1 : 0;
    }
  }
  EXPECT_GT(differ, 0u);
  options.frame = Aabb{{1.0, 0.0, 0.0}, {0.0, 1.0, 1.0}};
  try {
    (void)render_map(small, options);
    ADD_FAILURE() << "a frame with min > max was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("frame"), std::string::npos) << error.what();
  }
}

TEST(MapRenderSlice, CoarseLayerShowsTheMaximumOfItsVoxels) {
  const OccupancyMap map = free_box_map();
  RenderOptions options;
  options.slice = RenderSlice{2, 0.05};
  options.view = RenderView::top;
  options.color = RenderColor::state;
  options.depth = 1;  // z 0..0.2: the layer holding the occupied voxel (z index 1)
  options.width = 120;
  const MapPicture picture = render_map(map, options);
  // The depth-1 node over voxel (3, 2, 1) covers x 0.2..0.4, y 0.2..0.4: occupied.
  const auto [x, y] = picture.camera.pixel({0.25, 0.25, 0.1});
  EXPECT_EQ(picture.image.at(int(x), int(y)), options.occupied_color);
  const auto [x2, y2] = picture.camera.pixel({0.35, 0.35, 0.1});
  EXPECT_EQ(picture.image.at(int(x2), int(y2)), options.occupied_color);
  const auto [x3, y3] = picture.camera.pixel({0.45, 0.35, 0.1});
  EXPECT_EQ(picture.image.at(int(x3), int(y3)), options.free_color);
}

// --- color by depth, sections, state views -------------------------------------------

TEST(MapRender, DepthColorsRunFromNearRedToFarBlue) {
  OccupancyMap map(kResolution);
  map.set_log_odds(voxel(0, 0, 0), 2.0f);   // nearest to a viewer in the south (front view)
  map.set_log_odds(voxel(5, 10, 0), 2.0f);  // farthest
  map.set_log_odds(voxel(10, 5, 0), 2.0f);  // half way
  RenderOptions options;
  options.view = RenderView::front;
  options.color = RenderColor::depth;
  options.width = 200;
  const MapPicture picture = render_map(map, options);
  // The ramp's ends as coordinates on the view axis: far (low) and near (high).
  EXPECT_DOUBLE_EQ(picture.ramp_low, voxel(5, 10, 0).y);
  EXPECT_DOUBLE_EQ(picture.ramp_high, voxel(0, 0, 0).y);
  const double shade = documented_shade(documented_axes(RenderView::front), {0, -1, 0});
  auto at = [&](Vec3d p) {
    const auto [x, y] = picture.camera.pixel(p - Vec3d{0, 0.05, 0});  // on the face toward the viewer
    return picture.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
  };
  EXPECT_EQ(at(voxel(0, 0, 0)), shaded(height_ramp(1.0), shade));
  EXPECT_EQ(at(voxel(5, 10, 0)), shaded(height_ramp(0.0), shade));
  EXPECT_EQ(at(voxel(10, 5, 0)), shaded(height_ramp(0.5), shade));
}

TEST(MapRender, SectionLeavesOutWhatLiesBetweenThePlaneAndTheViewer) {
  OccupancyMap map(kResolution);
  map.set_log_odds(voxel(0, 0, 0), 2.0f);
  map.set_log_odds(voxel(0, 10, 0), 2.0f);
  map.set_log_odds(voxel(10, 10, 0), 2.0f);
  RenderOptions options;
  options.view = RenderView::front;  // the viewer is south (low y): y < 0.5 is in front
  options.section = 0.5;
  options.width = 200;
  EXPECT_EQ(render_map(map, options).nodes_drawn, 2u);
  options.section = 0.05;  // through the first voxel's middle: it reaches behind, so it stays
  EXPECT_EQ(render_map(map, options).nodes_drawn, 3u);
  options.view = RenderView::side;  // the viewer is east (high x): x > 0.5 is in front
  options.section = 0.5;
  EXPECT_EQ(render_map(map, options).nodes_drawn, 2u);
  options.section = 2.0;  // every voxel lies behind the plane
  EXPECT_EQ(render_map(map, options).nodes_drawn, 3u);
  options.section = -1.0;  // everything is in front of the plane
  EXPECT_THROW((void)render_map(map, options), std::invalid_argument);
}

TEST(MapRender, StateViewPaintsFreeAndUnknownSpaceBehindTheCubes) {
  // free_box_map with one column (7, 4, *) left unknown.
  OccupancyMap map(kResolution);
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 6; ++j) {
      for (int k = 0; k < 4; ++k) {
        if (i != 7 || j != 4) map.set_log_odds(voxel(i, j, k), -1.0f);
      }
    }
  }
  map.set_log_odds(voxel(3, 2, 1), 2.0f);
  RenderOptions options;
  options.view = RenderView::top;
  options.color = RenderColor::state;
  options.width = 220;
  const MapPicture picture = render_map(map, options);
  auto at = [&](Vec3d p) {
    const auto [x, y] = picture.camera.pixel(p);
    return picture.image.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
  };
  const double shade = documented_shade(documented_axes(RenderView::top), {0, 0, 1});
  EXPECT_EQ(at(voxel(3, 2, 3)), shaded(options.occupied_color, shade)) << "the obstacle, shaded";
  EXPECT_EQ(at(voxel(5, 1, 3)), options.free_color) << "free space seen from above";
  EXPECT_EQ(at(voxel(7, 4, 3)), options.unknown_color) << "a column nothing was seen in";
  // The frame is the known space (10 x 6 voxels), not the one obstacle.
  EXPECT_NEAR(picture.camera.metres_per_pixel, 1.0 / (options.width - 2 * options.margin_pixels), 1e-12);
  EXPECT_EQ(picture.image.at(0, 0), options.background);
  std::size_t counts[3] = {0, 0, 0};
  for (int row = 0; row < picture.image.height; ++row) {
    for (int column = 0; column < picture.image.width; ++column) {
      const Rgb c = picture.image.at(column, row);
      counts[0] += c == shaded(options.occupied_color, shade) ? 1 : 0;
      counts[1] += c == options.free_color ? 1 : 0;
      counts[2] += c == options.unknown_color ? 1 : 0;
    }
  }
  // Pixel areas: one voxel each for the obstacle and the hole, the rest free.
  const double voxel_pixels = std::pow(kResolution / picture.camera.metres_per_pixel, 2);
  EXPECT_NEAR(double(counts[0]), voxel_pixels, 4 * std::sqrt(voxel_pixels) + 4);
  EXPECT_NEAR(double(counts[2]), voxel_pixels, 4 * std::sqrt(voxel_pixels) + 4);
  EXPECT_NEAR(double(counts[1]), 58 * voxel_pixels, 4 * 58 * std::sqrt(voxel_pixels));
}

TEST(MapRenderSlice, OutsideTheKnownSpaceIsAnErrorNamingTheValueAndTheExtent) {
  const OccupancyMap map = free_box_map();  // known z from 0 to 0.4
  RenderOptions options;
  options.view = RenderView::top;
  options.color = RenderColor::state;
  for (const double z : {100.0, 0.4, -0.05, 1e9}) {
    options.slice = RenderSlice{2, z};
    try {
      (void)render_map(map, options);
      ADD_FAILURE() << "a slice at z = " << z << " was drawn";
    } catch (const std::invalid_argument& error) {
      const std::string message = error.what();
      std::ostringstream value;
      value << "z = " << z << " m";
      EXPECT_NE(message.find(value.str()), std::string::npos) << message;
      EXPECT_NE(message.find("spans z from 0 to 0.4 m"), std::string::npos) << message;
    }
  }
  options.slice = RenderSlice{2, 0.39};
  EXPECT_GT(render_map(map, options).nodes_drawn, 0u);
}

// --- the demo building against per-voxel lookups --------------------------------------

const OccupancyMap& demo_map() {
  static const OccupancyMap map = [] {
    MapConfig config;
    config.resolution = kResolution;
    return test::demo_lidar_map(config);
  }();
  return map;
}

/// Bounds (voxel index ranges) and height range of the occupied voxels.
struct OccupiedExtent {
  int low[3] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
  int high[3] = {std::numeric_limits<int>::min(), std::numeric_limits<int>::min(), std::numeric_limits<int>::min()};
};

OccupiedExtent occupied_extent(const OccupancyMap& map) {
  OccupiedExtent extent;
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.state != OccupancyState::occupied) return;
    const Vec3d low = leaf.min_corner();
    const Vec3d high = leaf.max_corner();
    for (std::size_t axis = 0; axis < 3; ++axis) {
      extent.low[axis] = std::min(extent.low[axis], static_cast<int>(std::lround(low[axis] / kResolution)));
      extent.high[axis] = std::max(extent.high[axis], static_cast<int>(std::lround(high[axis] / kResolution)) - 1);
    }
  });
  return extent;
}

TEST(MapRenderReference, AxisViewsOfTheDemoBuildingMatchPerVoxelLookups) {
  const OccupancyMap& map = demo_map();
  const OccupiedExtent extent = occupied_extent(map);
  const double z_low = (extent.low[2] + 0.5) * kResolution;
  const double z_high = (extent.high[2] + 0.5) * kResolution;
  for (const RenderView view : {RenderView::top, RenderView::front, RenderView::side}) {
    const Axes axes = documented_axes(view);
    // The axis along the picture's columns, along its rows, and toward the viewer.
    const auto right_axis = std::size_t(axes.right.x != 0 ? 0 : 1);
    const auto depth_axis = std::size_t(axes.toward.x != 0 ? 0 : (axes.toward.y != 0 ? 1 : 2));
    const int columns = extent.high[right_axis] - extent.low[right_axis] + 1;
    RenderOptions options;
    options.view = view;
    options.margin_pixels = 3;
    options.width = columns + 2 * options.margin_pixels;  // one pixel per voxel
    const MapPicture picture = render_map(map, options);
    ASSERT_NEAR(picture.camera.metres_per_pixel, kResolution, 1e-12) << to_string(view);
    EXPECT_DOUBLE_EQ(picture.ramp_low, z_low);
    EXPECT_DOUBLE_EQ(picture.ramp_high, z_high);
    Vec3d facing{};
    facing[depth_axis] = axes.toward[depth_axis];
    const double shade = documented_shade(axes, facing);
    const int step = axes.toward[depth_axis] > 0 ? -1 : 1;  // from the viewer into the scene
    const int first = step < 0 ? extent.high[depth_axis] : extent.low[depth_axis];
    const int last = step < 0 ? extent.low[depth_axis] : extent.high[depth_axis];

    std::size_t mismatches = 0;
    std::size_t drawn = 0;
    for (int row = 0; row < picture.image.height; ++row) {
      for (int column = 0; column < picture.image.width; ++column) {
        const double r = picture.camera.left + (column + 0.5) * kResolution;
        const double u = picture.camera.top - (row + 0.5) * kResolution;
        Vec3d p = axes.right * r + axes.up * u;
        Rgb expected = options.background;
        for (int k = first; k != last + step; k += step) {
          p[depth_axis] = (k + 0.5) * kResolution;
          if (map.state(p) == OccupancyState::occupied) {
            expected = shaded(height_ramp((p.z - z_low) / (z_high - z_low)), shade);
            break;
          }
        }
        const Rgb got = picture.image.at(column, row);
        drawn += got == options.background ? 0 : 1;
        if (got != expected && ++mismatches <= 5) {
          ADD_FAILURE() << to_string(view) << " pixel " << column << ", " << row << " is " << text(got)
                        << ", expected " << text(expected);
        }
      }
    }
    EXPECT_EQ(mismatches, 0u) << to_string(view);
    EXPECT_GT(drawn, std::size_t(picture.image.width)) << to_string(view);
  }
}

TEST(MapRenderReference, SlicesOfTheDemoBuildingMatchPerVoxelStates) {
  const OccupancyMap& map = demo_map();
  for (const RenderSlice slice : {RenderSlice{2, 1.23}, RenderSlice{1, 6.04}, RenderSlice{0, 10.11}}) {
    RenderOptions options;
    options.slice = slice;
    options.view = slice_view(slice.axis);
    options.color = RenderColor::state;
    options.margin_pixels = 2;
    // One pixel per voxel: the known space is a whole number of voxels wide.
    double low = std::numeric_limits<double>::infinity();
    double high = -low;
    const std::size_t right_axis = options.view == RenderView::side ? 1 : 0;
    map.for_each_leaf([&](const Node& leaf) {
      if (leaf.state == OccupancyState::unknown) return;
      low = std::min(low, leaf.min_corner()[right_axis]);
      high = std::max(high, leaf.max_corner()[right_axis]);
    });
    options.width = static_cast<int>(std::lround((high - low) / kResolution)) + 2 * options.margin_pixels;
    const MapPicture picture = render_map(map, options);
    ASSERT_NEAR(picture.camera.metres_per_pixel, kResolution, 1e-12);
    const Axes axes = documented_axes(options.view);
    const double plane = (std::floor(slice.position / kResolution) + 0.5) * kResolution;
    std::size_t counts[3] = {0, 0, 0};
    std::size_t mismatches = 0;
    for (int row = 0; row < picture.image.height; ++row) {
      for (int column = 0; column < picture.image.width; ++column) {
        Vec3d p = axes.right * (picture.camera.left + (column + 0.5) * kResolution) +
                  axes.up * (picture.camera.top - (row + 0.5) * kResolution);
        p[std::size_t(slice.axis)] = plane;
        const OccupancyState state = map.state(p);
        const Rgb expected = state == OccupancyState::occupied
                                 ? options.occupied_color
                                 : (state == OccupancyState::free ? options.free_color : options.unknown_color);
        ++counts[static_cast<int>(state == OccupancyState::occupied ? 0 : (state == OccupancyState::free ? 1 : 2))];
        if (picture.image.at(column, row) != expected && ++mismatches <= 5) {
          ADD_FAILURE() << "slice " << slice.axis << " pixel " << column << ", " << row << " is "
                        << text(picture.image.at(column, row)) << ", expected " << text(expected);
        }
      }
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_EQ(picture.nodes_drawn, leaves_in_slice(map, picture, slice.axis, slice.position));
    EXPECT_GT(counts[0], 10u) << "a slice through the building shows walls";
    EXPECT_GT(counts[1], 100u);
    EXPECT_GT(counts[2], 100u);
  }
}

// --- errors ---------------------------------------------------------------------------

TEST(MapRender, BadOptionsAreNamed) {
  const OccupancyMap map = free_box_map();
  auto expect_named = [&](const RenderOptions& options, const std::string& words) {
    try {
      (void)render_map(map, options);
      ADD_FAILURE() << "accepted options that should mention " << words;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
    }
  };
  RenderOptions options;
  options.width = 16;  // less than 2 * 8 + 1
  expect_named(options, "width");
  options = {};
  options.width = kMaxRenderPixels + 1;
  expect_named(options, "width");
  options = {};
  options.margin_pixels = -1;
  expect_named(options, "margin_pixels");
  options = {};
  options.depth = 17;  // above the map's 16 levels
  expect_named(options, "depth levels");
  options = {};
  options.depth = -1;
  expect_named(options, "depth");
  options = {};
  options.color = RenderColor::rgb;
  expect_named(options, "no color");
  options = {};
  options.slice = RenderSlice{3, 0.0};
  expect_named(options, "slice->axis");
  options = {};
  options.slice = RenderSlice{2, 0.5};  // view stays iso
  expect_named(options, "view");
  options.view = RenderView::top;
  options.slice->position = std::nan("");
  expect_named(options, "slice->position");
  options.slice->position = 1e7;
  expect_named(options, "outside the map");
  options.slice->position = 0.1;
  options.max_z = 1.0;
  expect_named(options, "min_z and max_z");
  options = {};
  options.min_z = 2.0;
  options.max_z = 1.0;
  expect_named(options, "max_z");
  options.max_z = std::numeric_limits<double>::infinity();
  expect_named(options, "max_z");

  EXPECT_THROW((void)render_map(OccupancyMap(0.1)), std::invalid_argument);  // nothing occupied
  RenderOptions slice;
  slice.slice = RenderSlice{2, 0.0};
  slice.view = RenderView::top;
  EXPECT_THROW((void)render_map(OccupancyMap(0.1), slice), std::invalid_argument);  // nothing known
}

// --- golden pictures --------------------------------------------------------------------
//
// Small pictures of the simulated demo building (16-ring LiDAR, 10 cm
// voxels, fixed seeds), compared with PNGs in tests/io/golden/. Tolerance,
// for harmless differences between compilers and libm versions (a ramp
// color rounding the other way, a face edge moving by a pixel): per
// channel, the mean absolute difference over the picture is at most 1.0,
// and at most 0.5% of the pixels differ by more than 24 in any channel. A
// real change (a view turned, colors swapped, faces missing) exceeds both.
// On a mismatch the new picture is written next to the test's temporary
// folder and its path printed. To accept new pictures after a deliberate
// change, run
//   UMBRA_UPDATE_GOLDEN=1 build/tests/io/umbra_io_tests --gtest_filter='RenderGolden.*'
// and commit tests/io/golden/*.png after looking at them.

/// The demo building mapped in color: each point colored by its position.
const OccupancyMap& colored_demo_map() {
  static const OccupancyMap map = [] {
    MapConfig config;
    config.resolution = 0.2;
    config.color = true;
    return test::demo_lidar_map(config, [](std::size_t, Vec3f p) {
      return Rgb{static_cast<std::uint8_t>(std::clamp(p.x * 12.0f, 0.0f, 255.0f)),
                 static_cast<std::uint8_t>(std::clamp(p.y * 20.0f, 0.0f, 255.0f)),
                 static_cast<std::uint8_t>(std::clamp(255.0f - p.z * 60.0f, 0.0f, 255.0f))};
    });
  }();
  return map;
}

struct Difference {
  double mean_abs = 0;        ///< per channel, over the picture
  double share_over_24 = 0;   ///< share of pixels with a channel off by more than 24
};

Difference compare(const Image& a, const Image& b) {
  Difference d;
  std::size_t over = 0;
  double total = 0;
  for (std::size_t pixel = 0; pixel < a.rgb.size() / 3; ++pixel) {
    int largest = 0;
    for (std::size_t channel = 0; channel < 3; ++channel) {
      const int diff = std::abs(int(a.rgb[3 * pixel + channel]) - int(b.rgb[3 * pixel + channel]));
      total += diff;
      largest = std::max(largest, diff);
    }
    over += largest > 24 ? 1 : 0;
  }
  d.mean_abs = total / double(a.rgb.size());
  d.share_over_24 = double(over) / double(a.rgb.size() / 3);
  return d;
}

void expect_matches_golden(const Image& picture, const std::string& name) {
  const std::filesystem::path golden = test::source_dir() / "tests" / "io" / "golden" / (name + ".png");
  if (std::getenv("UMBRA_UPDATE_GOLDEN") != nullptr) {
    write_png(picture, golden);
    std::printf("wrote %s\n", golden.c_str());
    return;
  }
  const std::filesystem::path failed = std::filesystem::temp_directory_path() / ("umbra-golden-" + name + ".png");
  if (!std::filesystem::exists(golden)) {
    write_png(picture, failed);
    FAIL() << golden << " is missing (this run's picture: " << failed
           << "); create it with UMBRA_UPDATE_GOLDEN=1 (see map_render_test.cpp)";
  }
  const Image expected = read_png(golden);
  if (expected.width != picture.width || expected.height != picture.height) {
    write_png(picture, failed);
    FAIL() << name << ": " << picture.width << " x " << picture.height << " pixels, golden " << expected.width
           << " x " << expected.height << " (this run's picture: " << failed << ")";
  }
  const Difference d = compare(picture, expected);
  const bool ok = d.mean_abs <= 1.0 && d.share_over_24 <= 0.005;
  if (!ok) write_png(picture, failed);
  EXPECT_TRUE(ok) << name << ": mean absolute difference " << d.mean_abs << " (at most 1.0), "
                  << 100 * d.share_over_24 << "% of pixels off by more than 24 (at most 0.5%); this run's picture: "
                  << failed;
}

TEST(RenderGolden, IsoByHeight) {
  RenderOptions options;
  options.width = 240;
  expect_matches_golden(render_map(demo_map(), options).image, "demo_iso_height");
}

TEST(RenderGolden, TopFrontSideByHeight) {
  for (const RenderView view : {RenderView::top, RenderView::front, RenderView::side}) {
    RenderOptions options;
    options.view = view;
    options.width = 200;
    options.margin_pixels = 4;
    expect_matches_golden(render_map(demo_map(), options).image, std::string("demo_") + to_string(view) + "_height");
  }
}

TEST(RenderGolden, CoarseIsoByState) {
  RenderOptions options;
  options.depth = 2;
  options.color = RenderColor::state;
  options.width = 200;
  expect_matches_golden(render_map(demo_map(), options).image, "demo_iso_depth2_state");
}

TEST(RenderGolden, SliceByState) {
  RenderOptions options;
  options.slice = RenderSlice{2, 1.2};
  options.view = RenderView::top;
  options.color = RenderColor::state;
  options.width = 200;
  expect_matches_golden(render_map(demo_map(), options).image, "demo_slice_z1.2_state");
}

TEST(RenderGolden, ColoredMapIsoByRgb) {
  RenderOptions options;
  options.color = RenderColor::rgb;
  options.width = 200;
  expect_matches_golden(render_map(colored_demo_map(), options).image, "demo_color_iso_rgb");
}

}  // namespace
}  // namespace umbra
