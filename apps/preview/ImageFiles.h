// ImageFiles: writes an image file through OpenImageIO with every write and
// the close checked. The image is encoded in memory and the file written
// with writeFileChecked (CacheFiles.h): OpenImageIO's own file writers do
// not report a failed write or close for every format, and an unknown
// extension leaves OIIO::geterror() empty.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <string>

namespace facet {

// Writes `image` to `path` in the format its extension names, with pixel
// type `format`. Returns "" or a one-line error naming the file.
std::string writeImageFile(const OIIO::ImageBuf& image, const std::string& path, OIIO::TypeDesc format);

}  // namespace facet
