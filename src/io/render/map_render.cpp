#include "umbra/io/map_render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "box_rasterizer.hpp"
#include "picture_annotations.hpp"
#include "umbra/io/topdown_image.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra {

namespace {

const char* axis_name(int axis) { return axis == 0 ? "x" : (axis == 1 ? "y" : "z"); }

template <typename Value>
[[noreturn]] void bad_option(const char* field, const std::string& requirement, const Value& value) {
  std::ostringstream out;
  out << "RenderOptions::" << field << " must be " << requirement << ", got " << value;
  throw std::invalid_argument(out.str());
}

/// A box in metres that grows to hold what is added.
struct Bounds {
  Vec3d min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
  Vec3d max = min * -1.0;
  [[nodiscard]] bool empty() const { return !(min.x <= max.x); }
  void add(Vec3d low, Vec3d high) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      min[axis] = std::min(min[axis], low[axis]);
      max[axis] = std::max(max[axis], high[axis]);
    }
  }
};

/// The ends of a color ramp: the lowest and highest value added.
struct RampRange {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double z) {
    low = std::min(low, z);
    high = std::max(high, z);
  }
};

/// What a picture frames: RenderOptions::frame when given, else `drawn`.
Bounds framed(const RenderOptions& options, const Bounds& drawn) {
  if (!options.frame) return drawn;
  Bounds box;
  box.add(options.frame->min, options.frame->max);
  return box;
}

struct Frame {
  RenderCamera camera;
  int width = 0;
  int height = 0;
};

/// The camera and picture size that fit `content` as map_render.hpp says.
Frame frame_for(RenderView view, const Bounds& content, const RenderOptions& options) {
  Frame frame;
  frame.camera = RenderCamera::axes_of(view);
  double right_low = std::numeric_limits<double>::infinity();
  double right_high = -right_low;
  double up_low = right_low;
  double up_high = -right_low;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d p{(corner & 1) != 0 ? content.max.x : content.min.x, (corner & 2) != 0 ? content.max.y : content.min.y,
                  (corner & 4) != 0 ? content.max.z : content.min.z};
    const double r = p.dot(frame.camera.right);
    const double u = p.dot(frame.camera.up);
    right_low = std::min(right_low, r);
    right_high = std::max(right_high, r);
    up_low = std::min(up_low, u);
    up_high = std::max(up_high, u);
  }
  const int margin = options.margin_pixels;
  double mpp = (right_high - right_low) / double(options.width - 2 * margin);
  mpp = std::max(mpp, (up_high - up_low) / double(kMaxRenderPixels - 2 * margin));
  // The rows the content needs; the slack keeps an exact fit (extent a whole
  // number of pixels, as when a pixel is one voxel) from gaining a row.
  const double rows = std::ceil((up_high - up_low) / mpp - 1e-9);
  frame.width = options.width;
  frame.height = static_cast<int>(std::max(1.0, rows)) + 2 * margin;
  frame.camera.metres_per_pixel = mpp;
  frame.camera.left = 0.5 * (right_low + right_high) - 0.5 * double(frame.width) * mpp;
  frame.camera.top = 0.5 * (up_low + up_high) + 0.5 * double(frame.height) * mpp;
  return frame;
}

/// The value a node has on the ramp of `color` (height or depth), seen through `camera`.
double ramp_value(const Node& node, RenderColor color, const RenderCamera& camera) {
  return color == RenderColor::depth ? node.center.dot(camera.toward) : node.center.z;
}

/// The color of an occupied node in the chosen color mode.
Rgb occupied_color(const Node& node, const RenderOptions& options, const RampRange& ramp,
                    const RenderCamera& camera) {
  switch (options.color) {
    case RenderColor::height:
    case RenderColor::depth: {
      const double value = ramp_value(node, options.color, camera);
      return height_ramp(ramp.high > ramp.low ? (value - ramp.low) / (ramp.high - ramp.low) : 0.0);
    }
    case RenderColor::rgb:
      return node.color.value_or(options.uncolored_color);
    case RenderColor::state:
      break;
  }
  return options.occupied_color;
}

/// The part of the map a view draws: the height window and the section.
Predicate view_window(const OccupancyMap& map, const RenderOptions& options) {
  if (!options.min_z && !options.max_z && !options.section) return pred::leaf();
  const double extent = map.grid().half_extent();
  Aabb window{{-extent, -extent, options.min_z.value_or(-extent)}, {extent, extent, options.max_z.value_or(extent)}};
  if (options.section && options.view == RenderView::front) window.min.y = *options.section;
  if (options.section && options.view == RenderView::side) window.max.x = *options.section;
  return pred::leaf() && pred::intersects(window);
}

/// The ramp's ends as MapPicture reports them: for depth the coordinates on
/// the view's axis of the farthest and nearest centre.
void report_ramp(MapPicture& picture, const RenderOptions& options, const RampRange& ramp) {
  if (options.color != RenderColor::height && options.color != RenderColor::depth) return;
  if (!(ramp.low <= ramp.high)) return;
  picture.ramp_low = ramp.low;
  picture.ramp_high = ramp.high;
  if (options.color == RenderColor::depth && options.view != RenderView::iso) {
    // toward is a unit axis, +-1: the coordinate is +-(distance along toward).
    const Vec3d& toward = picture.camera.toward;
    const double sign = toward.x + toward.y + toward.z;
    picture.ramp_low = sign * ramp.low;
    picture.ramp_high = sign * ramp.high;
  }
}

std::string window_words(const RenderOptions& options) {
  std::string words;
  if (options.min_z || options.max_z) words += " in the height window";
  if (options.section) words += std::string(words.empty() ? "" : " and") + " behind the section";
  return words;
}

MapPicture render_view(const OccupancyMap& map, const RenderOptions& options) {
  const Predicate window = view_window(map, options);
  const Predicate obstacles = window && pred::occupied();
  const bool by_state = options.color == RenderColor::state;
  const RenderCamera axes = RenderCamera::axes_of(options.view);
  Bounds content;
  RampRange ramp;
  std::size_t occupied = 0;
  for (const Node& node : map.query(obstacles, options.depth)) {
    content.add(node.min_corner(), node.max_corner());
    ramp.add(ramp_value(node, options.color, axes));
    ++occupied;
  }
  if (occupied == 0) {
    throw std::invalid_argument("render_map: the map has no occupied node at depth " + std::to_string(options.depth) +
                                window_words(options) +
                                ", so a view shows nothing (a slice shows free and unknown space)");
  }
  // With state colors the free space is drawn too: frame the known space.
  Bounds known = content;
  if (by_state) {
    for (const Node& node : map.query(window && pred::free(), options.depth)) known.add(node.min_corner(), node.max_corner());
  }
  const Frame frame = frame_for(options.view, framed(options, by_state ? known : content), options);
  MapPicture picture;
  picture.image = Image(frame.width, frame.height, options.background);
  picture.camera = frame.camera;
  picture.depth = options.depth;
  detail::BoxRasterizer rasterizer(frame.camera, picture.image);
  if (by_state) {
    // Behind every cube: the known box unknown, then what free space covers.
    rasterizer.paint_silhouette(known.min, known.max, options.unknown_color);
    for (const Node& node : map.query(window && pred::free(), options.depth)) {
      rasterizer.paint_silhouette(node.min_corner(), node.max_corner(), options.free_color);
    }
  }
  for (const Node& node : map.query(obstacles, options.depth)) {
    rasterizer.draw_box(node.min_corner(), node.max_corner(), occupied_color(node, options, ramp, frame.camera));
    ++picture.nodes_drawn;
  }
  report_ramp(picture, options, ramp);
  return picture;
}

/// Centre of the layer of depth-`depth` nodes holding `position` on the axis.
double slice_plane(const Grid& grid, double position, int depth) {
  const std::uint32_t key = *grid.axis_key(position);  // checked by check_render_options
  const std::uint32_t first = (key >> depth) << depth;
  return (double(first) - double(grid.key_offset()) + 0.5 * double(std::uint64_t{1} << depth)) * grid.resolution();
}

/// Paints the pixels whose centres lie in the node's rectangle (half-open,
/// so that the nodes of a slice, which tile it, paint every pixel once).
void paint_rectangle(Image& image, const RenderCamera& camera, const Node& node, Rgb color) {
  const auto [x0, y0] = camera.pixel(node.min_corner());
  const auto [x1, y1] = camera.pixel(node.max_corner());
  const int first_column = std::max(0, static_cast<int>(std::ceil(std::min(x0, x1) - 0.5)));
  const int end_column = std::min(image.width, static_cast<int>(std::ceil(std::max(x0, x1) - 0.5)));
  const int first_row = std::max(0, static_cast<int>(std::ceil(std::min(y0, y1) - 0.5)));
  const int end_row = std::min(image.height, static_cast<int>(std::ceil(std::max(y0, y1) - 0.5)));
  for (int row = first_row; row < end_row; ++row) {
    std::uint8_t* out = image.rgb.data() + 3 * (std::size_t(row) * std::size_t(image.width) + std::size_t(first_column));
    for (int column = first_column; column < end_column; ++column, out += 3) {
      out[0] = color.r;
      out[1] = color.g;
      out[2] = color.b;
    }
  }
}

MapPicture render_slice(const OccupancyMap& map, const RenderOptions& options) {
  const RenderSlice& slice = *options.slice;
  const auto axis = std::size_t(slice.axis);
  // The frame: the map's known space, the same for every slice along an axis.
  Bounds known;
  for (const Node& node : map.query(pred::leaf() && !pred::unknown(), 0)) known.add(node.min_corner(), node.max_corner());
  if (known.empty()) {
    throw std::invalid_argument("render_map: the map has no known space, so a slice shows nothing");
  }
  if (!(slice.position >= known.min[axis] && slice.position < known.max[axis])) {
    std::ostringstream out;
    out << "render_map: a slice at " << axis_name(slice.axis) << " = " << slice.position
        << " m is outside the map's known space, which spans " << axis_name(slice.axis) << " from "
        << known.min[axis] << " to " << known.max[axis] << " m";
    throw std::invalid_argument(out.str());
  }
  const Frame frame = frame_for(options.view, framed(options, known), options);

  // The plane through the layer's centre, over the picture (margins
  // included, shrunk by a millionth of a pixel so that nodes merely touching
  // its edges stay out): the leaves it meets are the layer's nodes there.
  const RenderCamera& camera = frame.camera;
  const double inset = 1e-6 * camera.metres_per_pixel;
  const double right_low = camera.left + inset;
  const double right_high = camera.left + double(frame.width) * camera.metres_per_pixel - inset;
  const double up_low = camera.top - double(frame.height) * camera.metres_per_pixel + inset;
  const double up_high = camera.top - inset;
  Aabb plane{camera.right * right_low + camera.up * up_low, camera.right * right_high + camera.up * up_high};
  for (std::size_t a = 0; a < 3; ++a) {
    if (plane.min[a] > plane.max[a]) std::swap(plane.min[a], plane.max[a]);
  }
  plane.min[axis] = plane.max[axis] = slice_plane(map.grid(), slice.position, options.depth);
  const Predicate layer = pred::leaf() && pred::intersects(plane);

  RampRange ramp;
  if (options.color == RenderColor::height) {
    for (const Node& node : map.query(layer && pred::occupied(), options.depth)) ramp.add(node.center.z);
  }
  MapPicture picture;
  picture.image = Image(frame.width, frame.height, options.background);
  picture.camera = frame.camera;
  picture.depth = options.depth;
  for (const Node& node : map.query(layer, options.depth)) {
    Rgb color = options.unknown_color;
    if (node.state == OccupancyState::occupied) {
      color = occupied_color(node, options, ramp, camera);
    } else if (node.state == OccupancyState::free) {
      color = options.free_color;
    }
    paint_rectangle(picture.image, picture.camera, node, color);
    ++picture.nodes_drawn;
  }
  report_ramp(picture, options, ramp);
  return picture;
}

/// The annotations' title: what the picture shows.
std::string picture_title(const OccupancyMap& map, const RenderOptions& options) {
  std::ostringstream out;
  const Grid& grid = map.grid();
  if (options.slice) {
    const double centre = slice_plane(grid, options.slice->position, options.depth);
    const double half = 0.5 * grid.node_size(options.depth);
    out << "slice " << axis_name(options.slice->axis) << " = " << options.slice->position << " m: the layer from "
        << centre - half << " to " << centre + half << " m";
  } else {
    out << to_string(options.view) << " view";
    if (options.min_z) out << ", z >= " << *options.min_z << " m";
    if (options.max_z) out << ", z <= " << *options.max_z << " m";
    if (options.section) out << ", " << (options.view == RenderView::front ? "y >= " : "x <= ") << *options.section << " m";
  }
  if (options.depth > 0) out << ", " << grid.node_size(options.depth) << " m nodes";
  return out.str();
}

}  // namespace

const char* to_string(RenderView view) {
  switch (view) {
    case RenderView::top: return "top";
    case RenderView::front: return "front";
    case RenderView::side: return "side";
    case RenderView::iso: return "iso";
  }
  return "?";
}

const char* to_string(RenderColor color) {
  switch (color) {
    case RenderColor::height: return "height";
    case RenderColor::rgb: return "rgb";
    case RenderColor::state: return "state";
    case RenderColor::depth: return "depth";
  }
  return "?";
}

RenderView slice_view(int axis) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("slice_view: axis must be 0, 1 or 2, got " + std::to_string(axis));
  static constexpr std::array<RenderView, 3> views{RenderView::side, RenderView::front, RenderView::top};
  return views[std::size_t(axis)];
}

RenderCamera RenderCamera::axes_of(RenderView view) {
  RenderCamera camera;
  switch (view) {
    case RenderView::top:
      camera.right = {1, 0, 0};
      camera.up = {0, 1, 0};
      camera.toward = {0, 0, 1};
      break;
    case RenderView::front:
      camera.right = {1, 0, 0};
      camera.up = {0, 0, 1};
      camera.toward = {0, -1, 0};
      break;
    case RenderView::side:
      camera.right = {0, 1, 0};
      camera.up = {0, 0, 1};
      camera.toward = {1, 0, 0};
      break;
    case RenderView::iso:
      camera.right = Vec3d{1, -1, 0} / std::sqrt(2.0);
      camera.up = Vec3d{1, 1, 2} / std::sqrt(6.0);
      camera.toward = Vec3d{-1, -1, 1} / std::sqrt(3.0);
      break;
  }
  return camera;
}

std::pair<double, double> RenderCamera::pixel(Vec3d point) const {
  return {(point.dot(right) - left) / metres_per_pixel, (top - point.dot(up)) / metres_per_pixel};
}

void RenderOptions::validate() const {
  if (margin_pixels < 0) bad_option("margin_pixels", ">= 0", margin_pixels);
  if (width < 2 * margin_pixels + 1 || width > kMaxRenderPixels) {
    bad_option("width", "in [2 * margin_pixels + 1, " + std::to_string(kMaxRenderPixels) + "] = [" +
                            std::to_string(2 * margin_pixels + 1) + ", " + std::to_string(kMaxRenderPixels) + "]",
               width);
  }
  if (2 * margin_pixels + 1 > kMaxRenderPixels) {
    bad_option("margin_pixels", "at most " + std::to_string((kMaxRenderPixels - 1) / 2), margin_pixels);
  }
  if (depth < 0 || depth > 21) bad_option("depth", "in [0, 21]", depth);
  if (min_z && !std::isfinite(*min_z)) bad_option("min_z", "finite", *min_z);
  if (max_z && !std::isfinite(*max_z)) bad_option("max_z", "finite", *max_z);
  if (min_z && max_z && *min_z > *max_z) bad_option("max_z", ">= min_z (" + std::to_string(*min_z) + ")", *max_z);
  if (annotate) {
    const detail::AnnotationLayout layout = detail::annotation_layout(*this);
    const int least = std::max(detail::kMinAnnotatedWidth, layout.left + layout.right + 2 * margin_pixels + 1);
    if (width < least) {
      bad_option("width", "at least " + std::to_string(least) + " with annotations (axes, legend, scale bar)", width);
    }
  }
  if (section && !std::isfinite(*section)) bad_option("section", "finite", *section);
  if (frame) {
    try {
      frame->validate();
    } catch (const std::invalid_argument& error) {
      bad_option("frame", "a box with finite corners and min <= max", error.what());
    }
  }
  if (section && view != RenderView::front && view != RenderView::side) {
    bad_option("section", "unset for a " + std::string(to_string(view)) +
                              " view (a section is for front and side views; a top view has max_z)",
               *section);
  }
  if (slice) {
    if (min_z || max_z) bad_option("min_z and max_z", "unset for a slice (a height window is for views)", "a window");
    if (section) bad_option("section", "unset for a slice (a section is for views)", *section);
    if (color == RenderColor::depth) bad_option("color", "height, rgb or state for a slice (a slice is flat)", "depth");
    if (slice->axis < 0 || slice->axis > 2) bad_option("slice->axis", "0 (x), 1 (y) or 2 (z)", slice->axis);
    if (!std::isfinite(slice->position)) bad_option("slice->position", "finite", slice->position);
    if (view != slice_view(slice->axis)) {
      bad_option("view", std::string(to_string(slice_view(slice->axis))) + " for a slice along " +
                             axis_name(slice->axis) + " (a slice is seen along its axis)",
                 to_string(view));
    }
  }
}

void check_render_options(const OccupancyMap& map, const RenderOptions& options) {
  options.validate();
  if (options.depth > map.depth_levels()) {
    bad_option("depth", "at most the map's depth levels (" + std::to_string(map.depth_levels()) + ")", options.depth);
  }
  if (options.color == RenderColor::rgb && !map.has_color()) {
    throw std::invalid_argument("RenderOptions::color is rgb, but the map has no color (use height or state)");
  }
}

MapPicture render_map(const OccupancyMap& map, const RenderOptions& options) {
  check_render_options(map, options);
  if (!options.annotate) return options.slice ? render_slice(map, options) : render_view(map, options);
  // The drawing, narrower by the gutters, then framed.
  const detail::AnnotationLayout layout = detail::annotation_layout(options);
  RenderOptions drawing = options;
  drawing.annotate = false;
  drawing.width = options.width - layout.left - layout.right;
  const MapPicture picture = options.slice ? render_slice(map, drawing) : render_view(map, drawing);
  return detail::annotate(picture, options, layout, picture_title(map, options));
}

}  // namespace umbra
