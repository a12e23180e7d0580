// Pictures of a map: its obstacles seen from a side, or a slice through it.
//
// render_map draws one of two kinds of picture, both with an orthographic
// camera (parallel projection: sizes do not shrink with distance):
//  - a view (no slice): every occupied node at the chosen depth drawn as a
//    solid cube, hidden faces removed with a depth buffer, each visible face
//    shaded by a fixed light so that the 3D shape reads. With the color
//    modes height, depth and rgb free and unknown space are not drawn (the
//    background shows through); with `state` they are painted behind the
//    cubes (see Colors).
//  - a slice: the layer of depth-`depth` nodes one node thick that contains
//    a coordinate on one axis, seen along that axis, every pixel painted by
//    the state of the node under it: occupied, free or unknown (the state
//    colors below, or for occupied nodes the color mode's color).
//
// Views (right = the picture's column direction, up = its row direction
// upwards, toward = from the scene to the viewer; right x up = toward):
//   top    right +x, up +y, toward +z        (looking down)
//   front  right +x, up +z, toward -y        (standing south, looking north)
//   side   right +y, up +z, toward +x        (standing east, looking west)
//   iso    right (1,-1,0)/sqrt 2, up (1,1,2)/sqrt 6, toward (-1,-1,1)/sqrt 3
//          (standing south-west and above, at 35.26 degrees elevation)
// A slice along z is drawn as the top view, along y as front, along x as side.
//
// What a view draws: the nodes whose cube meets the height window [min_z,
// max_z] and, for front and side views with a `section`, the half of the
// map behind the section plane (front: y >= section, side: x <= section),
// so that a front view looks into a building instead of at its outer wall.
// render_cuts.hpp finds the cuts a user usually wants (a ceiling, the middle).
//
// Colors: `height` puts each occupied node's centre height on height_ramp
// (topdown_image.hpp) between the lowest and highest drawn centre; `depth`
// puts its distance from the viewer on the same ramp, nearest red, farthest
// blue (for front and side views, where height would only repeat the row);
// `rgb` uses the node's color (maps with color only; a node without one
// gets `uncolored_color`); `state` paints occupied nodes `occupied_color`
// and, in a view, every pixel that no cube covers by what lies along its line
// of sight inside the drawn window: free_color where that line meets a free
// node, unknown_color where it crosses the box of the known space without
// meeting one, the background outside that box.
// A face's color is multiplied by 0.5 + 0.5 max(0, n.l), with n its normal
// and l = unit(toward + 0.8 up - 0.4 right): in the iso view the top faces
// are brightest and the faces to the right darkest; in the other views every
// visible face gets the same 0.87. Free and unknown space are not shaded.
//
// Framing: the picture is `width` pixels wide; the drawn content (a view:
// the box around the drawn nodes, with `state` around the drawn known space;
// a slice: the box around the map's known space) fills it less
// `margin_pixels` on each side, centred; the height follows from the
// content's aspect ratio (capped at kMaxRenderPixels, the content then
// shrinks to fit). MapPicture::camera maps points to pixels.
//
// Annotations (`annotate`, off by default; `umbra render` turns them on):
// the drawing is made narrower and framed by a title line (what is shown),
// for axis-aligned pictures coordinate ticks in metres along the left and
// bottom edges with the axis names, and a footer with the legend (the state
// colors, or the ramp with its two end values) and, for axis-aligned
// pictures, a scale bar; picture_annotations.hpp gives the layout. The
// picture stays `width` pixels wide and grows by the annotation rows.
//
// Cost model: the nodes come from OccupancyMap::query (pred::leaf() and
// pred::occupied(), or pred::intersects of the slice's plane), walked twice
// (framing, then drawing) without storing them; a node costs its query
// visit plus the pixels its faces cover. `state` in a view adds a walk over
// the free nodes in the window. Memory: the picture (3 bytes per pixel)
// plus a 4-byte depth per pixel for views.
#pragma once

#include <cstddef>
#include <optional>
#include <utility>

#include "umbra/core/aabb.hpp"
#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

enum class RenderView : unsigned char { top, front, side, iso };
enum class RenderColor : unsigned char { height, rgb, state, depth };

/// "top", "front", "side", "iso" / "height", "rgb", "state", "depth".
const char* to_string(RenderView view);
const char* to_string(RenderColor color);

/// Largest picture side render_map makes, in pixels.
inline constexpr int kMaxRenderPixels = 16384;
/// Narrowest picture with annotations, in pixels (the legend needs the room).
inline constexpr int kMinAnnotatedRenderWidth = 200;

/// A slice: the layer of nodes that contains `position` on `axis`.
struct RenderSlice {
  int axis = 2;           ///< 0 = x, 1 = y, 2 = z
  double position = 0.0;  ///< metres
};

/// The view a slice along `axis` is drawn with: top for z, front for y, side for x.
RenderView slice_view(int axis);

struct RenderOptions {
  RenderView view = RenderView::iso;
  RenderColor color = RenderColor::height;
  /// A slice instead of a view; `view` must then be slice_view(slice->axis).
  std::optional<RenderSlice> slice;
  /// Depth of the nodes drawn (0 = finest voxels); coarser nodes are drawn
  /// as their own cubes (occupied if any voxel in them is).
  int depth = 0;
  /// Height window of a view: only nodes whose cube meets z in [min_z,
  /// max_z] are drawn (e.g. to cut a building's ceiling away). Not for slices.
  std::optional<double> min_z;
  std::optional<double> max_z;
  /// Section plane of a front or side view, metres on the view's axis (front:
  /// y, side: x): only nodes whose cube reaches behind it, as the viewer sees
  /// it (front: y >= section, side: x <= section), are drawn.
  std::optional<double> section;
  /// The box (metres) the picture frames instead of what it draws (a view's
  /// nodes, a slice's known space): pictures of several maps, or of one map
  /// at several moments, then line up pixel for pixel. Drawing is unchanged
  /// (nodes outside the frame fall off the picture).
  std::optional<Aabb> frame;
  /// Title, axes, scale bar and legend around the drawing (see the top).
  bool annotate = false;
  int width = 1024;       ///< pixels, in [2 * margin_pixels + 1, kMaxRenderPixels]
  int margin_pixels = 8;  ///< >= 0
  Rgb background{255, 255, 255};
  Rgb occupied_color{200, 40, 40};    ///< state colors (slices, and views with `state`)
  Rgb free_color{200, 200, 200};
  Rgb unknown_color{32, 32, 40};
  Rgb uncolored_color{150, 150, 150};  ///< `rgb` for an occupied node that has no color

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// Where points land in a picture. Pixel (column, row) covers columns
/// [column, column + 1) and rows [row, row + 1) of pixel(point).
struct RenderCamera {
  Vec3d right;
  Vec3d up;
  Vec3d toward;                   ///< from the scene to the viewer
  double metres_per_pixel = 0.0;
  double left = 0.0;              ///< right-coordinate (metres) of the left edge of column 0
  double top = 0.0;               ///< up-coordinate (metres) of the top edge of row 0

  /// The axes of a view (metres_per_pixel, left and top stay 0).
  static RenderCamera axes_of(RenderView view);
  /// (column, row) as real numbers: ((p.right - left), (top - p.up)) / metres_per_pixel.
  [[nodiscard]] std::pair<double, double> pixel(Vec3d point) const;
};

struct MapPicture {
  Image image;
  RenderCamera camera;
  int depth = 0;                ///< depth of the nodes drawn
  /// Nodes drawn: a view, the occupied nodes; a slice, the layer's nodes
  /// (any state) that overlap the picture.
  std::size_t nodes_drawn = 0;
  /// The ends of the ramp, metres: `height` the lowest and highest centre z;
  /// `depth` the farthest and nearest centre's coordinate on the view axis
  /// (front: y, side: x, top: z; iso: the distance along toward). Both 0 for
  /// the other color modes.
  double ramp_low = 0.0;
  double ramp_high = 0.0;
};

/// Throws std::invalid_argument for options that do not fit `map`: a bad
/// field (validate()), a depth above the map's depth levels, `rgb` for a map
/// without color.
void check_render_options(const OccupancyMap& map, const RenderOptions& options);

/// Draws the picture described at the top of this file. Throws what
/// check_render_options throws, and std::invalid_argument when there is
/// nothing to draw (a view of a map without occupied space in its window, a
/// slice of a map without known space, a slice outside the known space: the
/// message names the position and the known space's extent on that axis).
MapPicture render_map(const OccupancyMap& map, const RenderOptions& options = {});

}  // namespace umbra
