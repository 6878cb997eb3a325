// ExrCodec: in-memory EXR encode and decode over OpenEXR's C++ API (see
// ExrCodec.h for why OpenEXR and not OpenImageIO).
#include "ExrCodec.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfVersion.h>
#include <OpenEXR/Iex.h>

#include <cstring>
#include <exception>
#include <fmt/format.h>

namespace facet {

namespace {

namespace Imf = OPENEXR_IMF_NAMESPACE;

// Reads from a byte string. OpenEXR expects read() past the end to throw.
class MemoryInput : public Imf::IStream {
public:
    explicit MemoryInput(const std::string& bytes) : Imf::IStream("table.exr"), bytes_(bytes) {}
    bool read(char c[], int n) override {
        if (n < 0 || uint64_t(n) > bytes_.size() - pos_) throw IEX_NAMESPACE::InputExc("unexpected end of file");
        std::memcpy(c, bytes_.data() + pos_, size_t(n));
        pos_ += uint64_t(n);
        return pos_ < bytes_.size();
    }
    uint64_t tellg() override { return pos_; }
    void seekg(uint64_t pos) override {
        if (pos > bytes_.size()) throw IEX_NAMESPACE::InputExc("seek past the end of the file");
        pos_ = pos;
    }

private:
    const std::string& bytes_;
    uint64_t pos_ = 0;
};

// Writes into a byte string; OpenEXR seeks back to fill in its offset table.
class MemoryOutput : public Imf::OStream {
public:
    explicit MemoryOutput(std::string& bytes) : Imf::OStream("table.exr"), bytes_(bytes) {}
    void write(const char c[], int n) override {
        if (n < 0) throw IEX_NAMESPACE::ArgExc("negative write");
        if (pos_ + uint64_t(n) > bytes_.size()) bytes_.resize(pos_ + uint64_t(n));
        std::memcpy(bytes_.data() + pos_, c, size_t(n));
        pos_ += uint64_t(n);
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = pos; }

private:
    std::string& bytes_;
    uint64_t pos_ = 0;
};

}  // namespace

std::string encodeExr(const ExrImage& image, std::string& bytes) {
    size_t nc = image.channels.size();
    if (image.width < 1 || image.height < 1 || nc == 0 ||
        image.pixels.size() != size_t(image.width) * size_t(image.height) * nc)
        return fmt::format("an EXR image of {} x {} with {} channels needs {} floats, got {}", image.width,
                           image.height, nc, size_t(image.width) * size_t(image.height) * nc, image.pixels.size());
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const auto& [name, value] : image.strings) header.insert(name, Imf::StringAttribute(value));
        for (const auto& [name, value] : image.ints) header.insert(name, Imf::IntAttribute(value));
        Imf::FrameBuffer frame;
        size_t xStride = nc * sizeof(float), yStride = xStride * size_t(image.width);
        for (size_t c = 0; c < nc; ++c) {
            header.channels().insert(image.channels[c], Imf::Channel(Imf::FLOAT));
            // OpenEXR only reads through the slice when writing.
            char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data() + c));
            frame.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base, xStride, yStride));
        }
        std::string out;
        MemoryOutput stream(out);
        {
            Imf::OutputFile file(stream, header, 0);  // 0: no worker threads, as a library must not start any
            file.setFrameBuffer(frame);
            file.writePixels(image.height);
        }  // the destructor writes the offset table
        bytes = std::move(out);
        return "";
    } catch (const std::exception& e) {
        return fmt::format("OpenEXR: {}", e.what());
    }
}

struct ExrReader::State {
    explicit State(const std::string& bytes) : stream(bytes) {}
    MemoryInput stream;
    std::unique_ptr<Imf::InputFile> file;
};

ExrReader::ExrReader(const std::string& bytes) : bytes_(bytes) {}
ExrReader::~ExrReader() = default;

std::string ExrReader::open(int maxDimension) {
    if (bytes_.size() < 8 || !Imf::isImfMagic(bytes_.data())) return "not an EXR file";
    int version = 0;
    std::memcpy(&version, bytes_.data() + 4, 4);  // EXR is little-endian, as is every host Facet runs on
    if (Imf::isTiled(version) || Imf::isMultiPart(version) || Imf::isNonImage(version))
        return "not a single-part scanline EXR";
    try {
        state_ = std::make_unique<State>(bytes_);
        // The header alone first: its data window is checked before
        // InputFile sizes its offset table by it.
        Imf::Header header;
        state_->stream.seekg(8);
        header.readFrom(state_->stream, version);
        const auto& window = header.dataWindow();
        int64_t w = int64_t(window.max.x) - window.min.x + 1, h = int64_t(window.max.y) - window.min.y + 1;
        if (w < 1 || h < 1 || w > maxDimension || h > maxDimension)
            return fmt::format("data window of {} x {} pixels (at most {} a side)", w, h, maxDimension);
        state_->stream.seekg(0);
        state_->file = std::make_unique<Imf::InputFile>(state_->stream, 0);
        const Imf::Header& hdr = state_->file->header();
        width_ = int(w);
        height_ = int(h);
        originX_ = hdr.dataWindow().min.x;
        originY_ = hdr.dataWindow().min.y;
        channels_.clear();
        for (auto it = hdr.channels().begin(); it != hdr.channels().end(); ++it) channels_.push_back(it.name());
        return "";
    } catch (const std::exception& e) {
        state_.reset();
        return fmt::format("OpenEXR: {}", e.what());
    }
}

std::string ExrReader::stringAttribute(const std::string& name) const {
    if (!state_ || !state_->file) return "";
    const auto* a = state_->file->header().findTypedAttribute<Imf::StringAttribute>(name);
    return a ? a->value() : "";
}

int ExrReader::intAttribute(const std::string& name, int fallback) const {
    if (!state_ || !state_->file) return fallback;
    const auto* a = state_->file->header().findTypedAttribute<Imf::IntAttribute>(name);
    return a ? a->value() : fallback;
}

std::string ExrReader::readPixels(const std::vector<std::string>& names, std::vector<float>& pixels) {
    if (!state_ || !state_->file) return "the file is not open";
    size_t nc = names.size();
    try {
        pixels.assign(size_t(width_) * size_t(height_) * nc, 0.0f);
        Imf::FrameBuffer frame;
        size_t xStride = nc * sizeof(float), yStride = xStride * size_t(width_);
        // The slice's base is the address of pixel (0, 0) of the data window's
        // coordinate system, so it is offset by the window's origin.
        char* origin = reinterpret_cast<char*>(pixels.data()) - int64_t(originX_) * int64_t(xStride) -
                       int64_t(originY_) * int64_t(yStride);
        for (size_t c = 0; c < nc; ++c) {
            if (!state_->file->header().channels().findChannel(names[c])) return fmt::format("no channel '{}'", names[c]);
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), xStride, yStride));
        }
        state_->file->setFrameBuffer(frame);
        state_->file->readPixels(originY_, originY_ + height_ - 1);
        return "";
    } catch (const std::exception& e) {
        return fmt::format("OpenEXR: {}", e.what());
    }
}

}  // namespace facet
