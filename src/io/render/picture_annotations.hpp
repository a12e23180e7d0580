// The annotations around a map picture (RenderOptions::annotate; private to
// umbra_io): a title, coordinate ticks, the legend and a scale bar, drawn
// with bitmap_font.hpp.
//
// Layout, with s the text scale (1 below 800 pixels of width, else 2) and
// the drawing (render_map's picture without annotations) at (left, top):
//   top     a title line over the drawing; for axis-aligned pictures the
//           name of the vertical axis ("y (m)") above the left gutter
//   left    axis-aligned pictures: ticks and their values in metres, right
//           aligned, for the vertical axis (room for 8 characters)
//   frame   a one-pixel line around the drawing
//   bottom  axis-aligned pictures: ticks and values for the horizontal axis
//           and its name; then the legend: the state colors as swatches,
//           or the ramp with its two ends in metres (height: low blue to
//           high red; depth: near red to far blue), or "map colors"; then,
//           for axis-aligned pictures, a scale bar of 1, 2 or 5 x 10^k
//           metres, the longest such not over a quarter of the drawing
// Tick spacing: the smallest 1, 2 or 5 x 10^k metres whose ticks lie at
// least 10 characters apart (horizontal axis) or 3 lines apart (vertical);
// values carry as many decimals as the step.
//
// Cost: the copy of the picture into the larger image, and the text.
#pragma once

#include <string>

#include "umbra/io/map_render.hpp"

namespace umbra::detail {

/// Narrowest annotated picture, in pixels (map_render.hpp).
inline constexpr int kMinAnnotatedWidth = kMinAnnotatedRenderWidth;

struct AnnotationLayout {
  int scale = 1;  ///< text scale
  int left = 0;   ///< pixels left of the drawing (gutter and frame)
  int right = 0;
  int top = 0;
  int bottom = 0;
};

/// The layout for a picture of options.width pixels (the drawing is
/// options.width - left - right wide).
AnnotationLayout annotation_layout(const RenderOptions& options);

/// The annotated picture: `drawing` framed as described above. Its camera is
/// the drawing's, moved so that it maps points to the annotated image.
MapPicture annotate(const MapPicture& drawing, const RenderOptions& options, const AnnotationLayout& layout,
                    const std::string& title);

/// Whether a picture of `options` is seen along a map axis (top, front,
/// side, and every slice): only those get axes and a scale bar.
bool axis_aligned(const RenderOptions& options);

}  // namespace umbra::detail
