// Tests of the annotations of map pictures (RenderOptions::annotate): the
// bitmap font's glyphs, and annotated pictures read back by the test: the
// drawing inside is the plain picture, the tick values (read with the
// font's own glyphs, matched cell by cell) are the coordinates at their
// ticks, the scale bar is as long as its label says, the legend shows the
// colors it names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bitmap_font.hpp"
#include "picture_annotations.hpp"
#include "support/room_map.hpp"
#include "umbra/io/map_render.hpp"
#include "umbra/io/topdown_image.hpp"

namespace umbra {
namespace {

using detail::glyph_pixel;
using detail::kGlyphAdvance;
using detail::kGlyphHeight;
using detail::kGlyphWidth;

const std::string kCharacters = "0123456789abcdefghijklmnopqrstuvwxyz.-()=,:<>/+";

TEST(BitmapFont, EveryCharacterHasItsOwnGlyph) {
  std::set<std::vector<bool>> seen;
  for (const char c : kCharacters) {
    EXPECT_TRUE(detail::has_glyph(c)) << c;
    std::vector<bool> cells;
    int set = 0;
    for (int row = 0; row < kGlyphHeight; ++row) {
      for (int column = 0; column < kGlyphWidth; ++column) {
        cells.push_back(glyph_pixel(c, column, row));
        set += cells.back() ? 1 : 0;
      }
    }
    EXPECT_GT(set, 1) << "'" << c << "' draws nothing";
    EXPECT_TRUE(seen.insert(cells).second) << "'" << c << "' looks like another character";
  }
  EXPECT_TRUE(detail::has_glyph(' '));
  EXPECT_TRUE(detail::has_glyph('X')) << "upper case is drawn as lower case";
  EXPECT_FALSE(detail::has_glyph('#'));
  EXPECT_TRUE(glyph_pixel('#', 0, 0)) << "a character without a glyph is a box, not nothing";
  EXPECT_FALSE(glyph_pixel('8', kGlyphWidth, 0));
  EXPECT_EQ(detail::text_width("2.5 m", 2), 5 * kGlyphAdvance * 2);
}

// --- reading text back ------------------------------------------------------------------

/// Whether the glyph of `c` is drawn at (left, top) in `color`: every cell
/// pixel is `color` exactly where the glyph is set, and not where it is clear.
bool glyph_at(const Image& image, int left, int top, char c, Rgb color, int scale) {
  if (left < 0 || top < 0 || left + kGlyphWidth * scale > image.width || top + kGlyphHeight * scale > image.height) {
    return false;
  }
  for (int row = 0; row < kGlyphHeight * scale; ++row) {
    for (int column = 0; column < kGlyphWidth * scale; ++column) {
      const bool ink = image.at(left + column, top + row) == color;
      if (ink != glyph_pixel(c, column / scale, row / scale)) return false;
    }
  }
  return true;
}

struct Word {
  std::string text;
  int left = 0;   ///< first cell's left column
  int right = 0;  ///< one past the last cell
};

/// The words written with cell tops at row `top` between columns [from, to):
/// glyphs found left to right, a space wherever a cell advance holds none.
std::vector<Word> read_words(const Image& image, int top, int from, int to, Rgb color, int scale) {
  std::vector<Word> words;
  for (int x = from; x < to;) {
    char found = 0;
    for (const char c : kCharacters) {
      if (glyph_at(image, x, top, c, color, scale)) {
        found = c;
        break;
      }
    }
    if (found == 0) {
      ++x;
      continue;
    }
    if (!words.empty() && words.back().right == x) {
      words.back().text += found;
    } else if (!words.empty() && words.back().right + kGlyphAdvance * scale == x) {
      words.back().text += std::string(" ") + found;  // one blank cell: a space inside the text
    } else {
      words.push_back({std::string(1, found), x, 0});
    }
    x += kGlyphAdvance * scale;
    words.back().right = x;
  }
  return words;
}

std::optional<double> as_number(const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') return std::nullopt;
  return value;
}

/// The rows of `image` in [from, to) holding any pixel of `color`, grouped in runs: their first rows.
std::vector<int> text_line_tops(const Image& image, int from, int to, Rgb color) {
  std::vector<int> tops;
  bool previous = false;
  for (int row = from; row < to; ++row) {
    bool any = false;
    for (int column = 0; column < image.width && !any; ++column) any = image.at(column, row) == color;
    if (any && !previous) tops.push_back(row);
    previous = any;
  }
  return tops;
}

constexpr Rgb kText{40, 40, 40};  // on the default white background
constexpr Rgb kLine{120, 120, 120};

TEST(PictureAnnotations, AnnotatedSliceReadsBackAsItsCoordinatesLegendAndScale) {
  const OccupancyMap room = test::closed_room_map();
  for (const int width : {420, 900}) {  // text scale 1 and 2
    RenderOptions options;
    options.slice = RenderSlice{2, 1.0};
    options.view = RenderView::top;
    options.color = RenderColor::state;
    options.width = width;
    options.annotate = true;
    const MapPicture annotated = render_map(room, options);
    const detail::AnnotationLayout layout = detail::annotation_layout(options);
    const int s = layout.scale;
    EXPECT_EQ(s, width >= 800 ? 2 : 1);
    ASSERT_EQ(annotated.image.width, width);

    // The drawing inside is the plain picture of the narrower width.
    RenderOptions plain = options;
    plain.annotate = false;
    plain.width = width - layout.left - layout.right;
    const MapPicture drawing = render_map(room, plain);
    ASSERT_EQ(annotated.image.height, drawing.image.height + layout.top + layout.bottom);
    for (int row = 0; row < drawing.image.height; ++row) {
      for (int column = 0; column < drawing.image.width; ++column) {
        ASSERT_EQ(annotated.image.at(column + layout.left, row + layout.top), drawing.image.at(column, row))
            << column << ", " << row;
      }
    }
    // The camera still maps points to the annotated image.
    const auto [x, y] = annotated.camera.pixel(test::room_voxel(30, 20, 10));
    const auto [dx, dy] = drawing.camera.pixel(test::room_voxel(30, 20, 10));
    EXPECT_NEAR(x, dx + layout.left, 1e-6);
    EXPECT_NEAR(y, dy + layout.top, 1e-6);

    // The title.
    const auto title = read_words(annotated.image, text_line_tops(annotated.image, 0, layout.top, kText).at(0),
                                  layout.left, width, kText, s);
    ASSERT_FALSE(title.empty());
    EXPECT_EQ(title[0].text, "slice z = 1 m: the layer from 1 to 1.1 m");

    // Horizontal ticks: grey marks under the frame; each value is the x at its column.
    const double mpp = annotated.camera.metres_per_pixel;
    const int below = layout.top + drawing.image.height + 1;  // the first row under the frame
    std::vector<int> tick_columns;
    for (int column = 0; column < width; ++column) {
      if (annotated.image.at(column, below) == kLine && (column == 0 || annotated.image.at(column - 1, below) != kLine)) {
        tick_columns.push_back(column);
      }
    }
    ASSERT_GE(tick_columns.size(), 2u);
    const std::vector<int> lines = text_line_tops(annotated.image, below, annotated.image.height, kText);
    ASSERT_GE(lines.size(), 4u) << "tick values, axis name, legend, scale bar";
    const std::vector<Word> values = read_words(annotated.image, lines[0], 0, width, kText, s);
    ASSERT_EQ(values.size(), tick_columns.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto value = as_number(values[i].text);
      ASSERT_TRUE(value.has_value()) << values[i].text;
      const double at_tick = annotated.camera.left + (tick_columns[i] + 0.5) * mpp;
      EXPECT_NEAR(*value, at_tick, 0.5 * mpp + 1e-9) << "tick " << i;
      EXPECT_NEAR(0.5 * (values[i].left + values[i].right), tick_columns[i], 3.0 * s) << "the value is under its tick";
    }
    const std::vector<Word> axis_name = read_words(annotated.image, lines[1], 0, width, kText, s);
    ASSERT_EQ(axis_name.size(), 1u);
    EXPECT_EQ(axis_name[0].text, "x (m)");

    // Vertical ticks: grey marks left of the frame; values right-aligned beside them.
    const int beside = layout.left - 2;
    std::size_t checked = 0;
    for (int row = layout.top; row < layout.top + drawing.image.height; ++row) {
      if (annotated.image.at(beside, row) != kLine || annotated.image.at(beside, row - 1) == kLine) continue;
      std::optional<double> value;
      for (int top = row - kGlyphHeight * s; top <= row && !value; ++top) {
        const auto words = read_words(annotated.image, top, 0, beside, kText, s);
        if (words.size() == 1) value = as_number(words[0].text);
      }
      ASSERT_TRUE(value.has_value()) << "no value beside the tick at row " << row;
      EXPECT_NEAR(*value, annotated.camera.top - (row + 0.5) * mpp, 0.5 * mpp + 1e-9) << "row " << row;
      ++checked;
    }
    EXPECT_GE(checked, 2u);
    const auto up_name = read_words(annotated.image, text_line_tops(annotated.image, 0, layout.top, kText).at(0), 0,
                                    layout.left, kText, s);
    ASSERT_EQ(up_name.size(), 1u);
    EXPECT_EQ(up_name[0].text, "y (m)");

    // The legend: a swatch of each state color, and the names.
    const std::vector<Word> legend = read_words(annotated.image, lines[2], 0, width, kText, s);
    std::string names;
    for (const Word& word : legend) names += word.text + "|";
    EXPECT_EQ(names, "occupied|free|unknown|");
    for (const Rgb color : {options.occupied_color, options.free_color, options.unknown_color}) {
      std::size_t swatch = 0;
      for (int row = lines[2]; row < lines[2] + kGlyphHeight * s; ++row) {
        for (int column = 0; column < width; ++column) swatch += annotated.image.at(column, row) == color ? 1 : 0;
      }
      EXPECT_GE(swatch, std::size_t(4 * s * s)) << "no swatch of a state color in the legend";
    }

    // The scale bar: "L m", then a bar of L metres.
    const std::vector<Word> scale = read_words(annotated.image, lines[3], 0, width, kText, s);
    ASSERT_EQ(scale.size(), 1u);
    ASSERT_EQ(scale[0].text.substr(scale[0].text.size() - 2), " m");
    const auto metres = as_number(scale[0].text.substr(0, scale[0].text.size() - 2));
    ASSERT_TRUE(metres.has_value()) << scale[0].text;
    int longest = 0;
    for (int row = lines[3]; row < lines[3] + kGlyphHeight * s; ++row) {
      int run = 0;
      for (int column = scale[0].right; column < width; ++column) {
        run = annotated.image.at(column, row) == kText ? run + 1 : 0;
        longest = std::max(longest, run);
      }
    }
    EXPECT_NEAR(longest * mpp, *metres, mpp) << "the bar is " << longest << " pixels";
    EXPECT_LE(*metres, 0.25 * drawing.image.width * mpp);
    EXPECT_GT(*metres, 0.25 * drawing.image.width * mpp / 2.5 - 1e-9) << "the longest 1-2-5 length under a quarter";
  }
}

TEST(PictureAnnotations, HeightLegendShowsTheRampBetweenItsEnds) {
  const OccupancyMap room = test::closed_room_map();
  RenderOptions options;
  options.view = RenderView::iso;
  options.width = 400;
  options.annotate = true;
  const MapPicture picture = render_map(room, options);
  const detail::AnnotationLayout layout = detail::annotation_layout(options);
  const int footer = picture.image.height - layout.bottom;
  // No axes for iso: no frame, no ticks; the legend row right below the drawing.
  EXPECT_EQ(picture.image.at(layout.left - 1, layout.top + 5), options.background);
  const std::vector<int> lines = text_line_tops(picture.image, footer, picture.image.height, kText);
  ASSERT_EQ(lines.size(), 1u);
  const auto words = read_words(picture.image, lines[0], 0, picture.image.width, kText, 1);
  ASSERT_EQ(words.size(), 2u);
  EXPECT_EQ(words[0].text, "height 0.05 m");  // the floor's centre ...
  EXPECT_EQ(words[1].text, "2.45 m");         // ... to the ceiling's
  // The strip between them (a space cell on either side) runs from the
  // ramp's low end to its high end.
  const int middle = lines[0] + 4;
  EXPECT_EQ(picture.image.at(words[0].right + kGlyphAdvance, middle), height_ramp(0.0));
  EXPECT_EQ(picture.image.at(words[1].left - kGlyphAdvance - 1, middle), height_ramp(1.0));
}

TEST(PictureAnnotations, TooNarrowForTheLegendIsAnErrorNamingTheWidth) {
  RenderOptions options;
  options.annotate = true;
  options.width = detail::kMinAnnotatedWidth - 1;
  try {
    options.validate();
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("width"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("annotations"), std::string::npos) << error.what();
  }
  options.width = detail::kMinAnnotatedWidth;
  EXPECT_NO_THROW(options.validate());
}

}  // namespace
}  // namespace umbra
