// ExrCodec: float EXR images encoded to and decoded from memory through
// OpenEXR itself, for the Kulla-Conty table files (TableCache.cpp).
//
// Why not OpenImageIO, which the previews use: OpenImageIO's shared library
// pulls in some 250 others (codecs, OpenCV, GDAL, ...), and every process
// that loaded a table paid ~0.35 s to map them: each `facet` command and
// every renderer linking libfacet.so. OpenEXR alone is six libraries. The
// files are the same EXR files as before (4 float channels, ZIP, string and
// int attributes) and any EXR reader opens them; OpenImageIO reads and
// writes them in the tests as the independent check.
//
// Every OpenEXR exception (a truncated or malformed file throws) becomes an
// error string; nothing here throws.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace facet {

// An image of float channels, interleaved: pixels[(y * width + x) * channels.size() + c].
struct ExrImage {
    int width = 0, height = 0;
    std::vector<std::string> channels;
    std::vector<float> pixels;
    std::map<std::string, std::string> strings;  // string attributes
    std::map<std::string, int> ints;             // int attributes
};

// Encodes `image` as a ZIP-compressed scanline EXR into `bytes`. Returns ""
// or a one-line error.
std::string encodeExr(const ExrImage& image, std::string& bytes);

// Reads an EXR held in memory in two steps, so that a caller can check the
// header (size, channels, attributes) before any pixel memory is allocated.
class ExrReader {
public:
    explicit ExrReader(const std::string& bytes);  // keeps a reference to `bytes`
    ~ExrReader();

    // Parses the header. Returns "" or why the bytes are not a readable
    // single-part scanline EXR of at most `maxDimension` pixels a side (checked
    // before OpenEXR sizes anything by the header's data window).
    std::string open(int maxDimension);

    // After open(): the data window's size and origin, the channel names
    // (sorted by name, as EXR stores them) and the attributes of the two
    // types Facet writes (absent ones: "" and `fallback`).
    int width() const { return width_; }
    int height() const { return height_; }
    int originX() const { return originX_; }
    int originY() const { return originY_; }
    const std::vector<std::string>& channels() const { return channels_; }
    std::string stringAttribute(const std::string& name) const;
    int intAttribute(const std::string& name, int fallback) const;

    // Reads the named channels (converted to float), interleaved in the
    // order given. Returns "" or why the pixels cannot be read.
    std::string readPixels(const std::vector<std::string>& names, std::vector<float>& pixels);

private:
    struct State;
    const std::string& bytes_;
    std::unique_ptr<State> state_;
    int width_ = 0, height_ = 0, originX_ = 0, originY_ = 0;
    std::vector<std::string> channels_;
};

}  // namespace facet
