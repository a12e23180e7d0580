#include "picture_annotations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bitmap_font.hpp"
#include "umbra/io/topdown_image.hpp"

namespace umbra::detail {

namespace {

// Vertical sizes in units of the text scale (a glyph cell is 9 high).
constexpr int kTick = 4;        // tick marks
constexpr int kGap = 2;         // tick to its value
constexpr int kLine = kGlyphHeight;
constexpr int kRowGap = 6;      // between the bottom rows
constexpr int kLabelChars = 8;  // room for a value on the vertical axis
constexpr int kPad = 4;
constexpr int kTickSpacingChars = 10;  // least distance of two ticks on the horizontal axis
constexpr int kTickSpacingLines = 3;   // and on the vertical one

const char* axis_letter(int axis) { return axis == 0 ? "x" : (axis == 1 ? "y" : "z"); }

/// The map axes along the picture's columns (right) and rows (up).
std::pair<int, int> picture_axes(RenderView view) {
  switch (view) {
    case RenderView::top: return {0, 1};
    case RenderView::front: return {0, 2};
    case RenderView::side: return {1, 2};
    case RenderView::iso: break;
  }
  return {-1, -1};
}

/// `value` with `decimals` decimals, never "-0".
std::string number(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  std::string out = text;
  if (out.find_first_not_of("-0.") == std::string::npos && out[0] == '-') out.erase(0, 1);
  return out;
}

/// A length in metres for the scale bar: "0.5", "2", "10" (no trailing zeros).
std::string length_text(double metres) {
  char text[64];
  std::snprintf(text, sizeof text, "%.6g", metres);
  return text;
}

/// Decimals that show every multiple of `step` (1, 2 or 5 x 10^k) exactly.
int decimals_of(double step) { return std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9))); }

/// The largest 1, 2 or 5 x 10^k that is at most `limit` (> 0).
double nice_at_most(double limit) {
  const double power = std::pow(10.0, std::floor(std::log10(limit)));
  for (const double factor : {5.0, 2.0, 1.0}) {
    if (factor * power <= limit * (1 + 1e-9)) return factor * power;
  }
  return power;
}

/// The smallest 1, 2 or 5 x 10^k that is at least `limit` (> 0).
double nice_at_least(double limit) {
  const double power = std::pow(10.0, std::floor(std::log10(limit)));
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    if (factor * power >= limit * (1 - 1e-9)) return factor * power;
  }
  return 10 * power;
}

struct Painter {
  Image& image;
  int scale;
  Rgb text;
  Rgb line;

  void fill(int x0, int y0, int width, int height, Rgb color) const {
    for (int y = std::max(0, y0); y < std::min(image.height, y0 + height); ++y) {
      for (int x = std::max(0, x0); x < std::min(image.width, x0 + width); ++x) image.set(x, y, color);
    }
  }
  void write(int x, int y, const std::string& words) const { draw_text(image, x, y, words, text, scale); }
  [[nodiscard]] int width_of(const std::string& words) const { return text_width(words, scale); }
  /// A swatch with a one-pixel outline, so that a color like the background shows.
  void swatch(int x, int y, Rgb color) const {
    const int side = kLine * scale - 2 * scale;
    fill(x, y + scale, side, side, line);
    fill(x + 1, y + scale + 1, side - 2, side - 2, color);
  }
};

Rgb text_color_on(Rgb background) {
  const int luminance = (299 * background.r + 587 * background.g + 114 * background.b) / 1000;
  return luminance > 128 ? Rgb{40, 40, 40} : Rgb{230, 230, 230};
}

/// The legend row: what the colors mean. Returns nothing; draws at (x, y).
void draw_legend(const Painter& paint, const MapPicture& drawing, const RenderOptions& options, int x, int y) {
  const int s = paint.scale;
  switch (options.color) {
    case RenderColor::state: {
      const std::vector<std::pair<Rgb, std::string>> entries{
          {options.occupied_color, "occupied"}, {options.free_color, "free"}, {options.unknown_color, "unknown"}};
      for (const auto& [color, name] : entries) {
        paint.swatch(x, y, color);
        x += kLine * s;
        paint.write(x, y, name);
        x += paint.width_of(name + "  ");
      }
      return;
    }
    case RenderColor::rgb:
      paint.write(x, y, "colors: the map's own");
      return;
    case RenderColor::height:
    case RenderColor::depth:
      break;
  }
  const bool by_height = options.color == RenderColor::height;
  std::string before;
  std::string after;
  if (by_height) {
    before = "height " + number(drawing.ramp_low, 2) + " m ";
    after = " " + number(drawing.ramp_high, 2) + " m";
  } else if (axis_aligned(options)) {
    const char* axis = axis_letter(options.view == RenderView::top ? 2 : (options.view == RenderView::front ? 1 : 0));
    before = std::string("near ") + axis + " = " + number(drawing.ramp_high, 2) + " m ";
    after = std::string(" far ") + axis + " = " + number(drawing.ramp_low, 2) + " m";
  } else {
    before = "near ";
    after = " far";
  }
  paint.write(x, y, before);
  x += paint.width_of(before);
  const int strip = 60 * s;
  for (int i = 0; i < strip; ++i) {
    const double t = double(i) / double(strip - 1);
    // Height runs low (blue) to high (red); depth near (red) to far (blue).
    paint.fill(x + i, y + s, 1, (kLine - 2) * s, height_ramp(by_height ? t : 1.0 - t));
  }
  paint.write(x + strip, y, after);
}

void draw_scale_bar(const Painter& paint, double metres_per_pixel, int drawing_width, int x, int y) {
  const int s = paint.scale;
  const double metres = nice_at_most(0.25 * double(drawing_width) * metres_per_pixel);
  const int pixels = static_cast<int>(std::lround(metres / metres_per_pixel));
  const std::string label = length_text(metres) + " m ";
  paint.write(x, y, label);
  x += paint.width_of(label);
  const int middle = y + (kGlyphRowsAboveBaseline * s) / 2;
  paint.fill(x, middle, pixels, s, paint.text);
  paint.fill(x, middle - 2 * s, s, 5 * s, paint.text);
  paint.fill(x + pixels - s, middle - 2 * s, s, 5 * s, paint.text);
}

/// Ticks at the multiples of a nice step between `low` and `high` metres.
std::vector<double> tick_values(double low, double high, double step) {
  std::vector<double> values;
  for (double k = std::ceil(low / step - 1e-9); k * step <= high + 1e-9 * step; k += 1) values.push_back(k * step);
  return values;
}

}  // namespace

bool axis_aligned(const RenderOptions& options) { return options.slice || options.view != RenderView::iso; }

AnnotationLayout annotation_layout(const RenderOptions& options) {
  AnnotationLayout layout;
  layout.scale = options.width >= 800 ? 2 : 1;
  const int s = layout.scale;
  layout.top = (kPad + kLine + kPad) * s;
  if (axis_aligned(options)) {
    layout.left = (kPad + kLabelChars * kGlyphAdvance + kGap + kTick) * s + 1;
    layout.right = (kLabelChars / 2) * kGlyphAdvance * s + 1;
    layout.bottom = 1 + (kTick + kGap + kLine + kGap + kLine + kRowGap + kLine + kRowGap + kLine + kPad) * s;
  } else {
    layout.left = kPad * s;
    layout.right = kPad * s;
    layout.bottom = (kRowGap + kLine + kPad) * s;
  }
  return layout;
}

MapPicture annotate(const MapPicture& drawing, const RenderOptions& options, const AnnotationLayout& layout,
                    const std::string& title) {
  const int s = layout.scale;
  const int width = drawing.image.width;
  const int height = drawing.image.height;
  MapPicture picture = drawing;
  picture.image = Image(width + layout.left + layout.right, height + layout.top + layout.bottom, options.background);
  const double mpp = drawing.camera.metres_per_pixel;
  picture.camera.left = drawing.camera.left - double(layout.left) * mpp;
  picture.camera.top = drawing.camera.top + double(layout.top) * mpp;
  for (int row = 0; row < height; ++row) {
    std::copy_n(drawing.image.rgb.begin() + 3 * std::ptrdiff_t(row) * width, 3 * width,
                picture.image.rgb.begin() + 3 * ((std::ptrdiff_t(row) + layout.top) * picture.image.width + layout.left));
  }
  const Painter paint{picture.image, s, text_color_on(options.background), Rgb{120, 120, 120}};
  const int x0 = layout.left;  // the drawing's corner in the annotated image
  const int y0 = layout.top;
  paint.write(x0, kPad * s, title);

  int y = y0 + height;  // the first row below the drawing
  if (axis_aligned(options)) {
    const auto [right_axis, up_axis] = picture_axes(options.view);
    // The frame.
    paint.fill(x0 - 1, y0 - 1, width + 2, 1, paint.line);
    paint.fill(x0 - 1, y0 + height, width + 2, 1, paint.line);
    paint.fill(x0 - 1, y0 - 1, 1, height + 2, paint.line);
    paint.fill(x0 + width, y0 - 1, 1, height + 2, paint.line);
    y += 1;
    // Horizontal axis: the coordinate at pixel edge c is left + c * mpp.
    const double step = nice_at_least(double(kTickSpacingChars * kGlyphAdvance * s) * mpp);
    const double left = drawing.camera.left;
    for (const double value : tick_values(left, left + double(width) * mpp, step)) {
      const int column = x0 + std::min(width - 1, static_cast<int>(std::floor((value - left) / mpp)));
      paint.fill(column, y, s, kTick * s, paint.line);
      const std::string label = number(value, decimals_of(step));
      paint.write(column - paint.width_of(label) / 2, y + (kTick + kGap) * s, label);
    }
    const std::string right_name = std::string(axis_letter(right_axis)) + " (m)";
    paint.write(x0 + width / 2 - paint.width_of(right_name) / 2, y + (kTick + kGap + kLine + kGap) * s, right_name);
    // Vertical axis: the coordinate at pixel edge r is top - r * mpp.
    const double up_step = nice_at_least(double(kTickSpacingLines * kLine * s) * mpp);
    const double top = drawing.camera.top;
    for (const double value : tick_values(top - double(height) * mpp, top, up_step)) {
      const int row = y0 + std::min(height - 1, static_cast<int>(std::floor((top - value) / mpp)));
      paint.fill(x0 - 1 - kTick * s, row, kTick * s, s, paint.line);
      const std::string label = number(value, decimals_of(up_step));
      paint.write(x0 - 1 - (kTick + kGap) * s - paint.width_of(label) + s, row - (kGlyphRowsAboveBaseline * s) / 2,
                  label);
    }
    const std::string up_name = std::string(axis_letter(up_axis)) + " (m)";
    paint.write(kPad * s, kPad * s, up_name);
    y += (kTick + kGap + kLine + kGap + kLine) * s;
  }
  y += kRowGap * s;
  draw_legend(paint, picture, options, x0, y);
  if (axis_aligned(options)) {
    y += (kLine + kRowGap) * s;
    draw_scale_bar(paint, mpp, width, x0, y);
  }
  return picture;
}

}  // namespace umbra::detail
