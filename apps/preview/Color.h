// Color: the colour helper shared by the sphere renderer and the plots.
#pragma once

namespace facet::preview {

// Rec. 709 / sRGB luminance of linear rgb.
inline double luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
inline double luminance(const float rgb[3]) { return luminance(rgb[0], rgb[1], rgb[2]); }

}  // namespace facet::preview
