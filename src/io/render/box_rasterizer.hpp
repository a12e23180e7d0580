// BoxRasterizer: draws solid axis-aligned boxes into an Image through an
// orthographic RenderCamera, with a depth buffer (private to umbra_io).
//
// A box shows at most three faces (those whose outward normal points toward
// the viewer); each is projected to a parallelogram and every pixel whose
// centre lies inside it (edges included, so that neighbouring faces leave no
// cracks) takes the face's shaded color if the face is nearer there than
// what the pixel shows. Depth is the distance along `toward`, exact for a
// plane face under a parallel projection (an affine function of the pixel
// position). Equal depths keep the first face drawn, so a picture depends
// only on the order of the calls.
//
// paint_silhouette paints the pixels a box covers in one flat color below
// everything drawn with draw_box: it neither tests nor writes the depth
// buffer (state pictures paint free and unknown space behind the cubes).
//
// Cost: per face, one test per pixel of its bounding rectangle; memory: a
// float per pixel for the depth buffer.
#pragma once

#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/png_writer.hpp"

namespace umbra::detail {

class BoxRasterizer {
 public:
  /// Draws into `image` (kept by reference; it must outlive the rasterizer).
  BoxRasterizer(const RenderCamera& camera, Image& image);

  /// The face shading factor 0.5 + 0.5 max(0, n.l) for a face with outward
  /// normal `normal` (map_render.hpp gives l).
  [[nodiscard]] double shade(Vec3d normal) const;

  /// Draws the box [min, max] in `color`, shaded per face.
  void draw_box(Vec3d min, Vec3d max, Rgb color);

  /// Paints the pixels the box [min, max] covers in `color`, unshaded, over
  /// what was painted before but not over cubes (call it before draw_box).
  void paint_silhouette(Vec3d min, Vec3d max, Rgb color);

 private:
  /// Calls face(corner, edge_a, edge_b, normal) for each face turned to the viewer.
  template <typename Face>
  void for_each_facing_face(Vec3d min, Vec3d max, Face&& face) const;
  void draw_face(Vec3d corner, Vec3d edge_a, Vec3d edge_b, Rgb color, bool depth_tested);

  RenderCamera camera_;
  Vec3d light_;
  Image& image_;
  std::vector<float> depth_;  ///< per pixel; -infinity where nothing is drawn
};

}  // namespace umbra::detail
