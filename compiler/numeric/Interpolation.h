// Interpolation: lookups in the float tables Facet's evaluators embed.
#pragma once

#include <cstddef>

namespace facet {

// Bilinear interpolation in a row-major float grid of rows of `rowLength`:
// between columns col, col + 1 at fraction s and rows row, row + 1 at
// fraction t, in double.
inline double bilinear(const float* grid, int rowLength, int row, int col, double s, double t) {
    const float* r0 = &grid[size_t(row) * rowLength + col];
    const float* r1 = r0 + rowLength;
    double a = r0[0] + (double(r0[1]) - r0[0]) * s;
    double b = r1[0] + (double(r1[1]) - r1[0]) * s;
    return a + (b - a) * t;
}

}  // namespace facet
