// ImageFiles: checked image writes (ImageFiles.h).
#include "ImageFiles.h"

#include "CacheFiles.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fmt/format.h>
#include <vector>

namespace facet {

std::string writeImageFile(const OIIO::ImageBuf& image, const std::string& path, OIIO::TypeDesc format) {
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput proxy(bytes);
    auto out = OIIO::ImageOutput::create(path, &proxy);
    if (!out) {
        std::string ext = OIIO::Filesystem::extension(path);
        std::string why = OIIO::geterror();
        if (why.empty())
            why = ext.empty() ? "the file name has no extension naming an image format (.png, .exr, ...)"
                              : fmt::format("'{}' is not an image format OpenImageIO can write (.png, .exr, ...)", ext);
        return fmt::format("cannot write {}: {}", path, why);
    }
    if (!out->supports("ioproxy"))
        return fmt::format("cannot write {}: the {} writer cannot be checked; use .png or .exr", path, out->format_name());
    OIIO::ImageSpec spec = image.spec();
    spec.set_format(format);
    auto fail = [&](std::string why) {
        if (why.empty()) why = "unknown OpenImageIO error";
        return fmt::format("cannot write {}: {}", path, why);
    };
    if (!out->open(path, spec)) return fail(out->geterror());
    if (!image.write(out.get())) return fail(image.geterror());
    if (!out->close()) return fail(out->geterror());
    return writeFileChecked(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace facet
