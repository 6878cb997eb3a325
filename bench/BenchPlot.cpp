// BenchPlot: a log-log scatter plot drawn pixel by pixel (see BenchPlot.h).
#include "BenchPlot.h"

#include "BitmapFont.h"
#include "ImageFiles.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace facet::bench {

namespace {

struct Rgb {
    uint8_t r, g, b;
};
constexpr Rgb kWhite{255, 255, 255}, kBlack{0, 0, 0}, kGrid{225, 225, 225}, kMinorGrid{242, 242, 242},
    kText{40, 40, 40}, kLeader{150, 150, 150};
// Material colours (colour-blind friendly, Okabe & Ito 2008), cycled.
constexpr Rgb kPalette[] = {{0, 114, 178}, {213, 94, 0},  {0, 158, 115}, {204, 121, 167},
                            {230, 159, 0}, {86, 180, 233}, {120, 120, 120}, {0, 0, 0}};

enum class Shape { Circle, Square, Triangle, Diamond };

class Canvas {
public:
    Canvas(int w, int h) : w_(w), h_(h), px_(size_t(w) * h * 3, 255) {}
    int width() const { return w_; }
    int height() const { return h_; }
    const uint8_t* data() const { return px_.data(); }

    void set(int x, int y, Rgb c) {
        if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
        uint8_t* p = &px_[(size_t(y) * w_ + x) * 3];
        p[0] = c.r, p[1] = c.g, p[2] = c.b;
    }
    void fillRect(int x0, int y0, int x1, int y1, Rgb c) {
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) set(x, y, c);
    }
    void rect(int x0, int y0, int x1, int y1, Rgb c) {
        line(x0, y0, x1, y0, c), line(x1, y0, x1, y1, c), line(x1, y1, x0, y1, c), line(x0, y1, x0, y0, c);
    }
    // Bresenham; `dash` > 0 draws dashes of that many pixels.
    void line(int x0, int y0, int x1, int y1, Rgb c, int dash = 0) {
        int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
        int err = dx + dy;
        for (int step = 0;; ++step) {
            if (!dash || (step / dash) % 2 == 0) set(x0, y0, c);
            if (x0 == x1 && y0 == y1) break;
            int e2 = 2 * err;
            if (e2 >= dy) err += dy, x0 += sx;
            if (e2 <= dx) err += dx, y0 += sy;
        }
    }
    // A marker of radius r: filled, or a 2-pixel outline.
    void marker(int cx, int cy, int r, Shape shape, Rgb c, bool filled) {
        auto inside = [&](double dx, double dy, double rr) {
            switch (shape) {
                case Shape::Circle: return dx * dx + dy * dy <= rr * rr;
                case Shape::Square: return std::fabs(dx) <= rr * 0.85 && std::fabs(dy) <= rr * 0.85;
                case Shape::Diamond: return std::fabs(dx) + std::fabs(dy) <= rr * 1.15;
                case Shape::Triangle: {  // pointing up, centred
                    double top = -rr, bottom = rr * 0.75;
                    if (dy < top || dy > bottom) return false;
                    double half = (dy - top) / (bottom - top) * rr * 1.05;
                    return std::fabs(dx) <= half;
                }
            }
            return false;
        };
        for (int y = -r - 1; y <= r + 1; ++y)
            for (int x = -r - 1; x <= r + 1; ++x)
                if (inside(x, y, r) && (filled || !inside(x, y, r - 2))) set(cx + x, cy + y, c);
    }
    // Text with its top-left corner at (x, y), glyph pixels scaled by `scale`.
    void text(int x, int y, const std::string& s, int scale, Rgb c) {
        for (char ch : s) {
            const auto& rows = glyph(ch);
            for (int row = 0; row < kGlyphHeight; ++row)
                for (int col = 0; col < kGlyphWidth; ++col)
                    if (rows[row] & (0x10 >> col)) fillRect(x + col * scale, y + row * scale, x + (col + 1) * scale - 1,
                                                            y + (row + 1) * scale - 1, c);
            x += kCellWidth * scale;
        }
    }
    // Text rotated a quarter turn counter-clockwise (reads bottom to top),
    // with the bottom-left of its first glyph at (x, y).
    void textUp(int x, int y, const std::string& s, int scale, Rgb c) {
        for (char ch : s) {
            const auto& rows = glyph(ch);
            for (int row = 0; row < kGlyphHeight; ++row)
                for (int col = 0; col < kGlyphWidth; ++col)
                    if (rows[row] & (0x10 >> col)) {
                        int px = x + row * scale, py = y - (col + 1) * scale;
                        fillRect(px, py, px + scale - 1, py + scale - 1, c);
                    }
            y -= kCellWidth * scale;
        }
    }
    static int textWidth(const std::string& s, int scale) {
        return s.empty() ? 0 : int(s.size()) * kCellWidth * scale - scale;
    }
    static int textHeight(int scale) { return kGlyphHeight * scale; }

private:
    int w_, h_;
    std::vector<uint8_t> px_;
};

Shape shapeOf(const std::string& backend) {
    if (backend == "simd") return Shape::Circle;
    if (backend == "scalar") return Shape::Square;
    if (backend == "interp") return Shape::Triangle;
    return Shape::Diamond;  // aot
}

std::string shortMode(const std::string& mode) {
    if (mode == "tol 1e-3") return "t1e-3";
    if (mode == "tol 1e-5") return "t1e-5";
    if (mode == "hand-written") return "";
    return mode;
}

// "1e-9", "0.01", "1", "100", "1e5": decade tick labels.
std::string decadeLabel(int k) {
    if (k >= 0 && k <= 4) return fmt::format("{}", int(std::lround(std::pow(10.0, k))));
    if (k >= -2 && k < 0) return fmt::format("{:.{}f}", std::pow(10.0, k), -k);
    return fmt::format("1e{}", k);
}

struct Box {
    int x0, y0, x1, y1;
    bool overlaps(const Box& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
};

struct Point {
    int material;
    std::string backend, label;
    double ns, maxRel, p999;
    int x = 0, y = 0, yp = 0;
    bool clippedTop = false;
};

}  // namespace

std::string writeScatterPlot(const BenchReport& report, const std::string& path) {
    const int W = kPlotWidth, H = kPlotHeight;
    const int left = 130, right = W - 400, top = 80, bottom = H - 110;  // the plot area
    Canvas cv(W, H);

    // Points: one per row; rows of one material and backend that land on
    // the same pixel share a label ("simd exact/fast").
    std::vector<Point> points;
    for (size_t mi = 0; mi < report.materials.size(); ++mi)
        for (const BenchRow& r : report.materials[mi].rows)
            if (r.nsPerEval > 0 && std::isfinite(r.nsPerEval))
                points.push_back({int(mi), r.backend, shortMode(r.mode), r.nsPerEval, r.regular.maxRel, r.regular.p999Rel});

    // Axis ranges in decades.
    double xlo = 0, xhi = 1, ylo = std::log10(kPlotErrorFloor), yhi = -2;
    if (!points.empty()) {
        double mn = INFINITY, mx = 0, emax = 0;
        for (const Point& p : points) {
            mn = std::min(mn, p.ns), mx = std::max(mx, p.ns);
            emax = std::max({emax, std::isfinite(p.maxRel) ? p.maxRel : 1e300, p.p999});
        }
        xlo = std::floor(std::log10(mn) - 0.05);
        xhi = std::ceil(std::log10(mx) + 0.05);
        yhi = std::clamp(std::ceil(std::log10(std::max(emax, kPlotErrorFloor)) + 0.05), ylo + 2, 3.0);
    }
    auto X = [&](double ns) { return left + int(std::lround((std::log10(ns) - xlo) / (xhi - xlo) * (right - left))); };
    auto Y = [&](double e, bool* clipped = nullptr) {
        double l = std::log10(std::max(e, kPlotErrorFloor));
        if (!std::isfinite(e) || l > yhi) {
            if (clipped) *clipped = true;
            l = yhi;
        }
        return bottom - int(std::lround((l - ylo) / (yhi - ylo) * (bottom - top)));
    };

    // Grid, ticks and tick labels.
    for (int k = int(xlo); k <= int(xhi); ++k) {
        for (int m = 2; m <= 9 && k < int(xhi); ++m) cv.line(X(m * std::pow(10.0, k)), top, X(m * std::pow(10.0, k)), bottom, kMinorGrid);
        int x = X(std::pow(10.0, k));
        cv.line(x, top, x, bottom, kGrid);
        cv.line(x, bottom, x, bottom + 8, kBlack);
        std::string t = decadeLabel(k);
        cv.text(x - Canvas::textWidth(t, 2) / 2, bottom + 14, t, 2, kText);
    }
    for (int k = int(ylo); k <= int(yhi); ++k) {
        int y = Y(std::pow(10.0, k));
        cv.line(left, y, right, y, kGrid);
        cv.line(left - 8, y, left, y, kBlack);
        std::string t = k == int(ylo) ? "<=" + decadeLabel(k) : decadeLabel(k);
        cv.text(left - 14 - Canvas::textWidth(t, 2), y - 7, t, 2, kText);  // centred on the 7-row body
    }
    cv.rect(left, top, right, bottom, kBlack);

    // Titles.
    std::string title = "facet bench: speed vs error";
    cv.text((left + right) / 2 - Canvas::textWidth(title, 3) / 2, 22, title, 3, kBlack);
    std::string xt = "ns per evaluation (log scale; lower is faster)";
    cv.text((left + right) / 2 - Canvas::textWidth(xt, 2) / 2, bottom + 50, xt, 2, kText);
    std::string yt = "relative error vs double interpreter (log)";
    cv.textUp(22, (top + bottom) / 2 + Canvas::textWidth(yt, 2) / 2, yt, 2, kText);

    // Points: positions, then groups of coinciding points.
    for (Point& p : points) {
        p.x = X(p.ns);
        p.y = Y(p.maxRel, &p.clippedTop);
        p.yp = Y(p.p999);
    }
    struct Group {
        int x, y, material;
        std::string text;
    };
    std::vector<Group> groups;
    for (size_t i = 0; i < points.size(); ++i) {
        const Point& p = points[i];
        bool merged = false;
        for (Group& g : groups)
            if (g.material == p.material && std::abs(g.x - p.x) <= 10 && std::abs(g.y - p.y) <= 10 &&
                g.text.rfind(p.backend, 0) == 0) {
                if (!p.label.empty() && p.backend != "interp") g.text += "/" + p.label;
                merged = true;
                break;
            }
        // The interpreter has no math modes: its rows differ only by timing noise.
        bool plain = p.label.empty() || p.backend == "interp";
        if (!merged) groups.push_back({p.x, p.y, p.material, plain ? p.backend : p.backend + " " + p.label});
    }

    // p99.9 markers and their links first, so that the max markers sit on top.
    for (const Point& p : points) {
        Rgb c = kPalette[p.material % std::size(kPalette)];
        if (p.yp != p.y) {
            cv.line(p.x, p.y, p.x, p.yp, c, 3);
            cv.marker(p.x, p.yp, 6, shapeOf(p.backend), c, false);
        }
    }
    std::vector<Box> occupied;
    for (const Point& p : points) {
        Rgb c = kPalette[p.material % std::size(kPalette)];
        cv.marker(p.x, p.y, 7, shapeOf(p.backend), c, true);
        if (p.clippedTop) cv.text(p.x - 5, p.y - 22, "^", 2, c);
        occupied.push_back({p.x - 8, p.y - 8, p.x + 8, p.y + 8});
    }

    // Labels: the first free spot among candidates around the point, at
    // growing distances (with a leader line once it is not adjacent).
    const int scale = 2, th = Canvas::textHeight(scale);
    for (const Group& g : groups) {
        int tw = Canvas::textWidth(g.text, scale);
        std::vector<std::pair<int, int>> candidates;  // top-left corners
        for (int d : {12, 30, 52, 80, 115})
            for (auto [ux, uy] : std::initializer_list<std::pair<int, int>>{
                     {1, 0}, {-1, 0}, {1, -1}, {1, 1}, {-1, -1}, {-1, 1}, {0, -1}, {0, 1}}) {
                int x = ux > 0 ? g.x + d : ux < 0 ? g.x - d - tw : g.x - tw / 2;
                int y = uy > 0 ? g.y + d - th / 2 : uy < 0 ? g.y - d - th / 2 : g.y - th / 2;
                if (uy != 0 && ux == 0) y = uy > 0 ? g.y + d : g.y - d - th;
                candidates.push_back({x, y});
            }
        Box chosen{};
        bool found = false;
        for (auto [x, y] : candidates) {
            Box b{x - 2, y - 2, x + tw + 2, y + th + 2};
            if (b.x0 < left + 2 || b.x1 > right - 2 || b.y0 < top + 2 || b.y1 > bottom - 2) continue;
            if (std::any_of(occupied.begin(), occupied.end(), [&](const Box& o) { return o.overlaps(b); })) continue;
            chosen = b;
            found = true;
            break;
        }
        if (!found) {  // crowded: right of the point, clamped into the plot
            int x = std::clamp(g.x + 12, left + 4, right - tw - 4), y = std::clamp(g.y - th / 2, top + 4, bottom - th - 4);
            chosen = {x - 2, y - 2, x + tw + 2, y + th + 2};
        }
        int cx = std::clamp(g.x, chosen.x0, chosen.x1), cy = std::clamp(g.y, chosen.y0, chosen.y1);
        if (std::hypot(cx - g.x, cy - g.y) > 14) cv.line(g.x, g.y, cx, cy, kLeader);
        cv.fillRect(chosen.x0, chosen.y0, chosen.x1, chosen.y1, kWhite);
        cv.text(chosen.x0 + 2, chosen.y0 + 2, g.text, scale, kPalette[g.material % std::size(kPalette)]);
        occupied.push_back(chosen);
    }

    // Legend: materials (colour), backends (shape), the two error markers.
    int lx = right + 30, ly = top;
    cv.text(lx, ly, "materials", 2, kBlack);
    ly += 26;
    for (size_t mi = 0; mi < report.materials.size(); ++mi) {
        Rgb c = kPalette[mi % std::size(kPalette)];
        cv.fillRect(lx, ly, lx + 16, ly + 14, c);
        std::string name = report.materials[mi].material;
        if (name.size() > 26) name = name.substr(0, 25) + "~";
        cv.text(lx + 26, ly, name, 2, kText);
        ly += 24;
    }
    ly += 16;
    cv.text(lx, ly, "backends", 2, kBlack);
    ly += 26;
    for (auto [b, what] : {std::pair{"simd", "simd (JIT)"}, {"scalar", "scalar (JIT)"},
                           {"interp", "interp (reference)"}, {"aot", "aot (hand-written)"}}) {
        cv.marker(lx + 8, ly + 7, 7, shapeOf(b), kText, true);
        cv.text(lx + 26, ly, what, 2, kText);
        ly += 24;
    }
    ly += 16;
    cv.text(lx, ly, "y: regular sample", 2, kBlack);
    ly += 26;
    cv.marker(lx + 8, ly + 7, 7, Shape::Circle, kText, true);
    cv.text(lx + 26, ly, "max rel. error", 2, kText);
    ly += 24;
    cv.marker(lx + 8, ly + 7, 6, Shape::Circle, kText, false);
    cv.text(lx + 26, ly, "p99.9 rel. error", 2, kText);
    ly += 24;
    cv.text(lx, ly, fmt::format("errors < {:g} drawn", kPlotErrorFloor), 2, kText);
    ly += 20;
    cv.text(lx, ly, "on the floor; ^ = off scale", 2, kText);
    ly += 36;
    cv.text(lx, ly, "labels: backend mode", 2, kBlack);
    ly += 24;
    cv.text(lx, ly, "t1e-3 = tolerance=1e-3", 2, kText);
    ly += 20;
    if (report.settings.quick) cv.text(lx, ly + 10, "QUICK RUN (noisy)", 2, Rgb{200, 0, 0});

    // Write through OpenImageIO.
    OIIO::ImageSpec spec(W, H, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Software", "facet bench");
    OIIO::ImageBuf image(spec, const_cast<uint8_t*>(cv.data()));  // wraps the canvas
    return writeImageFile(image, path, OIIO::TypeDesc::UINT8);
}

}  // namespace facet::bench
