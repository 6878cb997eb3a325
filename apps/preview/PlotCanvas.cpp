// PlotCanvas: ImageBufAlgo drawing for the `facet render` plots (see
// PlotCanvas.h). The only rasterization here is OIIO's; this file turns
// thick, dashed and curved strokes into the one-pixel lines, boxes and glyphs
// that ImageBufAlgo draws, and checks what this OIIO build's text support
// can do.
#include "PlotCanvas.h"

#include "ImageFiles.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace facet::preview {

namespace {

namespace IBA = OIIO::ImageBufAlgo;

// A supersampled canvas this large (pixels) would need hundreds of MB even
// at 8 bits per channel; beyond it the canvas draws at output resolution.
constexpr long long kMaxSupersampledPixels = 64ll << 20;

bool isReadableFile(const std::string& path) {
    std::error_code ec;
    return !path.empty() && std::filesystem::is_regular_file(path, ec);
}

// Code points in a UTF-8 string (continuation bytes are not counted).
size_t codePoints(std::string_view s) {
    return size_t(std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// `text` drawn alone, black on white, into a small scratch image.
OIIO::ImageBuf renderAlone(std::string_view text, const std::string& font) {
    OIIO::ImageBuf img(OIIO::ImageSpec(64, 64, 3, OIIO::TypeDesc::UINT8));
    const float white[3] = {1, 1, 1}, black[3] = {0, 0, 0};
    IBA::fill(img, white);
    IBA::render_text(img, 8, 48, text, 40, font, black);
    return img;
}

}  // namespace

std::string findPlotFont(bool monospace) {
    if (const char* env = std::getenv("FACET_FONT"); env && isReadableFile(env)) return env;
    // Debian/Ubuntu (fonts-dejavu-core), Fedora, older Fedora/openSUSE, Arch.
    static constexpr const char* kDirs[] = {
        "/usr/share/fonts/truetype/dejavu/", "/usr/share/fonts/dejavu-sans-fonts/",
        "/usr/share/fonts/dejavu-sans-mono-fonts/", "/usr/share/fonts/dejavu/",
        "/usr/share/fonts/TTF/", "/usr/local/share/fonts/",
    };
    const char* order[2] = {"DejaVuSans.ttf", "DejaVuSansMono.ttf"};
    if (monospace) std::swap(order[0], order[1]);
    for (const char* file : order)
        for (const char* dir : kDirs)
            if (std::string path = std::string(dir) + file; isReadableFile(path)) return path;
    return "";
}

std::string noTextWarning(const PlotCanvas& canvas, const std::string& font) {
    if (canvas.hasFont()) return "";
    if (font.empty())
        return "no TrueType font found (install fonts-dejavu-core or set FACET_FONT to a .ttf file): "
               "the plot is drawn without text";
    return "cannot draw text with font '" + font + "': the plot is drawn without text";
}

std::string checkPlotSize(int width, int height) {
    if (width < kMinPlotSize || height < kMinPlotSize || width > kMaxPlotSize || height > kMaxPlotSize)
        return "plot size " + std::to_string(width) + " x " + std::to_string(height) + " is outside " +
               std::to_string(kMinPlotSize) + " .. " + std::to_string(kMaxPlotSize) + " pixels per side";
    return "";
}

std::string plotFontOrDefault(const std::string& requested) { return requested.empty() ? findPlotFont() : requested; }

double plotFontSize(int width, int height) { return std::clamp(std::min(width, height * 8 / 5) / 64.0, 7.0, 48.0); }

void noteNoRoomForText(const PlotCanvas& canvas, bool textDrawn, std::string& warning) {
    if (canvas.hasFont() && !textDrawn)
        warning = std::to_string(canvas.width()) + " x " + std::to_string(canvas.height()) +
                  " pixels is too small for legible labels: the plot is drawn without text";
}

PlotCanvas::PlotCanvas(int width, int height, const std::string& fontPath, Rgb background, int supersample)
    : width_(std::max(width, 1)), height_(std::max(height, 1)), ss_(std::max(supersample, 1)) {
    if (static_cast<long long>(width_) * height_ * ss_ * ss_ > kMaxSupersampledPixels) ss_ = 1;
    // 8 bits per channel: the output is 8-bit for PNG anyway, and it keeps a
    // large supersampled canvas at a quarter of the float size.
    buf_.reset(OIIO::ImageSpec(width_ * ss_, height_ * ss_, 3, OIIO::TypeDesc::UINT8));
    const float bg[3] = {background.r, background.g, background.b};
    IBA::fill(buf_, bg);

    if (!isReadableFile(fontPath)) return;
    // OIIO's text_size returns garbage without a font name, and may in some
    // builds with one: accept its measure only when a digit comes out about
    // as wide and tall as a digit is.
    OIIO::ROI digit = IBA::text_size("0", 20, fontPath);
    measureWorks_ = digit.defined() && digit.width() >= 5 && digit.width() <= 20 && digit.height() >= 8 &&
                    digit.height() <= 30;
    OIIO::ImageBuf zero = renderAlone("0", fontPath);
    if (IBA::isConstantColor(zero)) return;  // the font did not load or draws nothing
    font_ = fontPath;
    // Some OIIO builds drop the high bits of non-ASCII code points, which
    // draws U+00B0 as '0' (0xB0 & 0x7F = '0'): the degree sign is only used
    // when it comes out as a glyph different from that.
    OIIO::ImageBuf degree = renderAlone("\xC2\xB0", fontPath);
    IBA::CompareResults same = IBA::compare(degree, zero, 0.0f, 0.0f);
    degreeSign_ = !IBA::isConstantColor(degree) && same.maxerror > 0;
}

int PlotCanvas::px(double v) const {
    double s = v * ss_;
    // Far-off coordinates (a clipped curve's outliers) stay representable;
    // render_line clips them to the image.
    s = std::clamp(s, -1e6, 1e6);
    return int(std::lround(s));
}

void PlotCanvas::solidSegment(Point a, Point b, Rgb color, double width) {
    const float c[3] = {color.r, color.g, color.b};
    double ax = a.x * ss_, ay = a.y * ss_, bx = b.x * ss_, by = b.y * ss_;
    double dx = bx - ax, dy = by - ay, len = std::hypot(dx, dy);
    double w = std::max(width * ss_, 1.0);
    if (len < 0.5) {  // a dot
        int h = int(std::lround(w / 2));
        IBA::render_box(buf_, px(a.x) - h, px(a.y) - h, px(a.x) + h, px(a.y) + h, c, true);
        return;
    }
    // Parallel one-pixel lines one pixel apart along the minor axis cover
    // the band without gaps; a band of n such lines is n cos(slope) wide
    // across the segment, so n = w / cos(slope) gives the requested width.
    bool mostlyHorizontal = std::abs(dx) >= std::abs(dy);
    double cosSlope = std::max(std::abs(dx), std::abs(dy)) / len;
    int n = std::max(1, int(std::lround(w / cosSlope)));
    for (int k = 0; k < n; ++k) {
        double off = k - (n - 1) / 2.0;
        double ox = mostlyHorizontal ? 0 : off, oy = mostlyHorizontal ? off : 0;
        IBA::render_line(buf_, int(std::lround(std::clamp(ax + ox, -1e6, 1e6))),
                         int(std::lround(std::clamp(ay + oy, -1e6, 1e6))),
                         int(std::lround(std::clamp(bx + ox, -1e6, 1e6))),
                         int(std::lround(std::clamp(by + oy, -1e6, 1e6))), c);
    }
}

void PlotCanvas::line(Point a, Point b, const Stroke& stroke) { polyline({a, b}, stroke); }

void PlotCanvas::polyline(const std::vector<Point>& input, const Stroke& stroke) {
    // Vertices closer than a pixel to the last one kept only add rounding
    // jitter (each segment snaps its ends to the pixel grid): drop them,
    // keeping the last vertex so that the line ends where it should.
    std::vector<Point> points;
    points.reserve(input.size());
    for (size_t i = 0; i < input.size(); ++i) {
        const Point& p = input[i];
        bool last = i + 1 == input.size();
        if (points.empty() || last || !std::isfinite(p.x) || !std::isfinite(p.y) ||
            std::hypot(p.x - points.back().x, p.y - points.back().y) >= 1.0)
            points.push_back(p);
    }
    if (points.size() < 2) return;
    bool dashed = stroke.dash > 0 && stroke.gap > 0;
    double period = stroke.dash + stroke.gap;
    double phase = 0;  // distance into the current dash period
    for (size_t i = 1; i < points.size(); ++i) {
        Point a = points[i - 1], b = points[i];
        if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) continue;
        if (!dashed) {
            solidSegment(a, b, stroke.color, stroke.width);
            // Thick strokes get a square at each inner vertex so that sharp
            // turns show no notch.
            if (stroke.width > 1.5 && i + 1 < points.size()) {
                double h = stroke.width / 2;
                box({b.x - h, b.y - h}, {b.x + h, b.y + h}, stroke.color, true);
            }
            continue;
        }
        double len = std::hypot(b.x - a.x, b.y - a.y);
        auto at = [&](double s) { return Point{a.x + (b.x - a.x) * s / len, a.y + (b.y - a.y) * s / len}; };
        for (double s = 0; s < len;) {
            bool on = phase < stroke.dash;
            double step = std::min((on ? stroke.dash : period) - phase, len - s);
            if (on) solidSegment(at(s), at(s + step), stroke.color, stroke.width);
            s += step;
            phase += step;
            if (phase >= period - 1e-9) phase = 0;
        }
    }
}

void PlotCanvas::box(Point a, Point b, Rgb color, bool fill, double width) {
    const float c[3] = {color.r, color.g, color.b};
    int x0 = px(std::min(a.x, b.x)), x1 = px(std::max(a.x, b.x));
    int y0 = px(std::min(a.y, b.y)), y1 = px(std::max(a.y, b.y));
    if (fill) {
        IBA::render_box(buf_, x0, y0, x1, y1, c, true);
        return;
    }
    // An outline `width` wide: nested one-pixel outlines, growing inwards.
    int n = std::max(1, int(std::lround(width * ss_)));
    for (int k = 0; k < n && x0 + k <= x1 - k && y0 + k <= y1 - k; ++k)
        IBA::render_box(buf_, x0 + k, y0 + k, x1 - k, y1 - k, c, false);
}

void PlotCanvas::polygon(const std::vector<Point>& vertices, Rgb color, bool fill, double width) {
    if (vertices.size() < 3) return;
    if (!fill) {
        std::vector<Point> closed = vertices;
        closed.push_back(vertices.front());
        // The closing vertex is an inner vertex too: no notch where the outline starts.
        closed.push_back(vertices[1]);
        polyline(closed, {color, width});
        return;
    }
    // Even-odd scanline fill in the supersampled grid: each pixel row whose
    // centre crosses the polygon gets one horizontal render_line per span.
    const float c[3] = {color.r, color.g, color.b};
    double ymin = INFINITY, ymax = -INFINITY;
    for (const Point& v : vertices) ymin = std::min(ymin, v.y * ss_), ymax = std::max(ymax, v.y * ss_);
    if (!std::isfinite(ymin) || !std::isfinite(ymax)) return;
    int row0 = std::max(0, int(std::floor(ymin))), row1 = std::min(height_ * ss_ - 1, int(std::ceil(ymax)));
    std::vector<double> crossings;
    for (int row = row0; row <= row1; ++row) {
        double y = row + 0.5;
        crossings.clear();
        for (size_t i = 0; i < vertices.size(); ++i) {
            Point a = vertices[i], b = vertices[(i + 1) % vertices.size()];
            double ay = a.y * ss_, by = b.y * ss_;
            if ((ay <= y) == (by <= y)) continue;  // the edge does not cross this row
            crossings.push_back((a.x + (b.x - a.x) * (y - ay) / (by - ay)) * ss_);
        }
        std::sort(crossings.begin(), crossings.end());
        for (size_t i = 0; i + 1 < crossings.size(); i += 2) {
            int x0 = int(std::lround(std::clamp(crossings[i], -1e6, 1e6)));
            int x1 = int(std::lround(std::clamp(crossings[i + 1], -1e6, 1e6))) - 1;
            if (x1 >= x0) IBA::render_line(buf_, x0, row, x1, row, c);
        }
    }
}

void PlotCanvas::arc(Point center, double radius, double a0, double a1, const Stroke& stroke) {
    // A vertex every ~2 output pixels of arc length: smooth after downsampling.
    int n = std::max(8, int(std::ceil(std::abs(a1 - a0) * radius / 2)));
    std::vector<Point> pts(size_t(n) + 1);
    for (int i = 0; i <= n; ++i) {
        double a = a0 + (a1 - a0) * i / n;
        pts[size_t(i)] = {center.x + radius * std::cos(a), center.y - radius * std::sin(a)};
    }
    polyline(pts, stroke);
}

bool PlotCanvas::text(Point at, std::string_view text, double size, Rgb color, HAlign h, VAlign v) {
    if (font_.empty() || text.empty()) return false;
    // OIIO 2.4's render_text aborts (an assertion on an empty region) when the
    // text falls wholly outside the image: an anchor off the canvas draws nothing.
    if (!(at.x >= 0 && at.x <= width_ && at.y >= 0 && at.y <= height_)) return false;
    const float c[3] = {color.r, color.g, color.b};
    auto ax = h == HAlign::Left ? IBA::TextAlignX::Left
              : h == HAlign::Center ? IBA::TextAlignX::Center : IBA::TextAlignX::Right;
    auto ay = v == VAlign::Baseline ? IBA::TextAlignY::Baseline
              : v == VAlign::Top    ? IBA::TextAlignY::Top
              : v == VAlign::Center ? IBA::TextAlignY::Center : IBA::TextAlignY::Bottom;
    int fontSize = std::max(1, int(std::lround(size * ss_)));
    return IBA::render_text(buf_, px(at.x), px(at.y), text, fontSize, font_, c, ax, ay);
}

double PlotCanvas::textWidth(std::string_view text, double size) const {
    // DejaVu Sans: digits are 0.64 em wide, lower-case letters 0.5-0.65 em.
    double estimate = 0.62 * size * double(codePoints(text));
    if (!measureWorks_ || text.empty()) return estimate;
    OIIO::ROI r = IBA::text_size(text, std::max(1, int(std::lround(size * ss_))), font_);
    if (!r.defined()) return estimate;
    double w = double(r.width()) / ss_;
    // A measure far from the estimate is garbage, not a font quirk.
    return w > 0.2 * estimate && w < 3 * estimate ? w : estimate;
}

OIIO::ImageBuf PlotCanvas::resolved() const {
    if (ss_ == 1) return buf_.copy(OIIO::TypeDesc::UNKNOWN);
    // Averaging each ss x ss block (a box filter of its default width, one
    // output pixel) is what antialiases the strokes; wider filters only blur.
    return IBA::resize(buf_, "box", 0.0f, OIIO::ROI(0, width_, 0, height_, 0, 1, 0, 3));
}

std::string PlotCanvas::write(const std::string& path) const {
    OIIO::ImageBuf out = resolved();
    if (out.has_error()) return "cannot downsample the plot: " + out.geterror();
    std::string ext = OIIO::Filesystem::extension(path, false);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    OIIO::TypeDesc format = ext == "exr" ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8;
    return writeImageFile(out, path, format);
}

}  // namespace facet::preview
