// A tiny bitmap font for the labels of map pictures (private to umbra_io):
// the digits, the lower-case letters and ". - ( ) = , : < > / +", each a
// 5 x 9 pixel cell (digits and capitals' height 7 rows, rows 7 and 8 for
// the descenders of g j p q y), advanced by 6 pixels, drawn `scale` times
// larger. umbra's own design, so that pictures need no font library; an
// upper-case letter is drawn as its lower-case one, any other character as
// a hollow box (never silently dropped).
//
// Cost: a few table lookups per pixel of text.
#pragma once

#include <string_view>

#include "umbra/core/color.hpp"
#include "umbra/io/png_writer.hpp"

namespace umbra::detail {

inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 9;
inline constexpr int kGlyphAdvance = 6;  ///< the glyph and one column of space
inline constexpr int kGlyphRowsAboveBaseline = 7;

/// Whether pixel (column, row) of the glyph of `c` is set (column in [0, 5),
/// row in [0, 9); false outside).
bool glyph_pixel(char c, int column, int row);

/// Whether the font has a glyph of its own for `c` (not the hollow box).
bool has_glyph(char c);

/// Width of `text` in pixels at `scale` (the last glyph's trailing space included).
int text_width(std::string_view text, int scale);

/// Draws `text` with its cells' top-left corner at (left, top); pixels
/// outside the image are skipped.
void draw_text(Image& image, int left, int top, std::string_view text, Rgb color, int scale);

}  // namespace umbra::detail
