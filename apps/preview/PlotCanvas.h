// PlotCanvas: a small drawing surface for the diagnostic plots of
// `facet render` (Plots.cpp) and the scatter plot of `facet bench`
// (bench/BenchPlot.cpp), over an OpenImageIO ImageBuf.
//
// Everything is drawn with ImageBufAlgo (render_line, render_box,
// render_text) into an RGB float buffer at `supersample` times the output
// resolution; write() downsamples it with ImageBufAlgo::resize, which is what
// antialiases the one-pixel lines and hard glyph edges. Callers work in
// output pixels (x right, y down, doubles), never in the supersampled grid.
//
// Text needs a TrueType font, passed to OIIO by path (findPlotFont). Without
// one the canvas still draws lines and boxes, text() does nothing and
// hasFont() is false, so that a plot degrades to an unlabelled picture
// instead of failing.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <string>
#include <string_view>
#include <vector>

namespace facet::preview {

struct Rgb {
    float r = 0, g = 0, b = 0;
};

struct Point {
    double x = 0, y = 0;
};

// Where a text's anchor point sits relative to the text.
enum class HAlign { Left, Center, Right };
enum class VAlign { Baseline, Top, Center, Bottom };

// How a line is stroked: width in output pixels; dash > 0 draws dashes of
// that length separated by gaps of `gap` (output pixels).
struct Stroke {
    Rgb color;
    double width = 1;
    double dash = 0, gap = 0;
};

// The TrueType font for plot labels: $FACET_FONT if it names a readable file,
// else the first DejaVu font found in the usual Debian/Fedora/Arch places
// (monospace: DejaVuSansMono first). "" when there is none.
std::string findPlotFont(bool monospace = false);

class PlotCanvas;
// Why a plot drawn on `canvas` with `font` (findPlotFont's answer or a
// requested file) has no text, or "" when the canvas draws text.
std::string noTextWarning(const PlotCanvas& canvas, const std::string& font);

// Plot sizes `facet render` draws, output pixels per side.
constexpr int kMinPlotSize = 64, kMaxPlotSize = 8192;
// "" or why width x height is outside kMinPlotSize .. kMaxPlotSize.
std::string checkPlotSize(int width, int height);
// `requested` if not empty, else findPlotFont().
std::string plotFontOrDefault(const std::string& requested);
// Label text size for a plot: ~15 px at 960 x 600, in proportion to the
// smaller of width and (wide-screen) height.
double plotFontSize(int width, int height);
// Sets `warning` when the canvas could draw text but the layout left none
// (`textDrawn` false): the plot is too small for legible labels.
void noteNoRoomForText(const PlotCanvas& canvas, bool textDrawn, std::string& warning);

class PlotCanvas {
public:
    // A width x height (output pixels) canvas filled with `background`.
    // `fontPath` may be "" (no text). Sizes must be positive.
    PlotCanvas(int width, int height, const std::string& fontPath, Rgb background = {1, 1, 1}, int supersample = 2);

    int width() const { return width_; }
    int height() const { return height_; }

    // True when text can be drawn (the font loaded and rendered a test glyph).
    bool hasFont() const { return !font_.empty(); }
    const std::string& fontPath() const { return font_; }
    // True when the font renders U+00B0 (the degree sign) as its own glyph:
    // some OpenImageIO builds map non-ASCII code points to wrong ASCII
    // glyphs, so a label should fall back to "deg" when this is false.
    bool rendersDegreeSign() const { return degreeSign_; }

    void line(Point a, Point b, const Stroke& stroke);
    // Connected segments; dashes continue across vertices.
    void polyline(const std::vector<Point>& points, const Stroke& stroke);
    // Axis-aligned box with corners a and b; filled or a one-`width` outline.
    void box(Point a, Point b, Rgb color, bool fill, double width = 1);
    // Closed polygon through `vertices`: filled (even-odd rule), or a
    // one-`width` outline.
    void polygon(const std::vector<Point>& vertices, Rgb color, bool fill, double width = 1);
    // Circular arc around `center`, radius r (output pixels), from angle a0
    // to a1 in radians measured counter-clockwise from +x (y up on screen).
    void arc(Point center, double radius, double a0, double a1, const Stroke& stroke);

    // Draws UTF-8 `text` of nominal height `size` (output pixels) anchored at
    // `at`. Returns false (drawing nothing) without a font.
    bool text(Point at, std::string_view text, double size, Rgb color, HAlign h = HAlign::Left,
              VAlign v = VAlign::Baseline);
    // Width of `text` at `size`, output pixels: measured with the font when
    // OIIO's text_size works for it, else estimated from the character count.
    double textWidth(std::string_view text, double size) const;

    // Downsamples to the output size and writes `path` in the format its
    // extension names: 8 bits per channel, or half float for EXR. Returns ""
    // or an error message.
    std::string write(const std::string& path) const;

    // The downsampled output image (what write() writes).
    OIIO::ImageBuf resolved() const;

private:
    // Output pixels -> supersampled pixel index.
    int px(double v) const;
    // One solid segment `width` output pixels wide, as parallel one-pixel
    // render_line strokes offset along the segment's minor axis.
    void solidSegment(Point a, Point b, Rgb color, double width);

    int width_, height_, ss_;
    OIIO::ImageBuf buf_;
    std::string font_;         // "" when text cannot be drawn
    bool measureWorks_ = false;  // OIIO text_size gives plausible numbers
    bool degreeSign_ = false;
};

}  // namespace facet::preview
