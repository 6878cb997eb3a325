// BitmapFont: a 5x7 pixel font (with 2 rows of descenders) for printable
// ASCII, for the bench plot.
//
// The plot is drawn into a plain pixel buffer and written with OpenImageIO,
// so its text needs a font that ships with the source: these glyphs were
// drawn by hand for this file (one byte per row, bit 4 = leftmost pixel),
// in the style of the classic 5x7 LCD character sets. Rows 0-6 hold the
// letter above the baseline, rows 7-8 the descenders of g j p q y , ;.
// Text advances by a 6-pixel cell: one column between glyphs.
#pragma once

#include <array>
#include <cstdint>

namespace facet::bench {

constexpr int kGlyphWidth = 5, kGlyphHeight = 9;  // 7 rows + 2 for descenders
constexpr int kCellWidth = 6, kCellHeight = 11;

// Rows of the glyph of `c` (printable ASCII; anything else draws as '?').
const std::array<uint8_t, kGlyphHeight>& glyph(char c);

}  // namespace facet::bench
