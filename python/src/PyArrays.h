// PyArrays: NumPy arrays in and out of the facet module, as the SoA columns
// the kernels read and write (facet.h: three rows of n floats per vector).
//
// Vectors (directions, the sampler's u, rgb inputs) come as (N, 3) or (3, N)
// arrays, or one vector of shape (3,); a (3, 3) array is read as (N, 3).
// A (3, N) C-contiguous array of the element type the call computes in
// (float32 for compiled kernels, float64 for the interpreter) is read in
// place; anything else numeric goes through one conversion,
// numpy.ascontiguousarray(transposed if (N, 3), dtype) -- a single copy.
// Results take the layout of the call's first vector argument: a (3, N)
// array comes back (3, N), an (N, 3) one as the (N, 3) transpose of the
// kernel's (3, N) output (a view, no copy), one vector as shape (3,).
//
// Wrong types raise TypeError and wrong shapes or lengths ValueError, each
// naming the argument and what was expected (never a crash).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <vector>

namespace facet::python {

namespace py = pybind11;

enum class Layout { Single, RowsOfThree, ThreeRows };  // (3,), (N, 3), (3, N)

// Three rows of n values, read from a Python object.
template <typename T>
struct Vectors3 {
    int64_t n = 0;
    Layout layout = Layout::Single;
    const T* rows[3] = {};
    bool copied = false;  // went through the conversion
    py::array held;       // the (3, n) array the rows point into
};

// Reads `value` (argument `arg` of the call) as vectors of 3.
template <typename T>
Vectors3<T> readVectors3(py::handle value, const char* arg);

// Makes a single vector (or n = 1) stand for `n` lanes; a batch must have
// exactly n. `other` names the argument that set n, for the message.
template <typename T>
void matchLanes(Vectors3<T>& v, int64_t n, const char* arg, const char* other);

// One value per lane for a float input: a number, a length-1 array
// (broadcast) or a length-n array. In place when it is a C-contiguous
// array of T already. Given the input's declared range, values that come in
// double (a Python float, a float64 array) are clamped to it before they
// are rounded to a float T: 1e39 for an input in 0 .. 1 is 1, not Inf (the
// kernels clamp too, but only what float can hold; facet.h asks callers to
// clamp in double first).
template <typename T>
struct LaneValues {
    const T* data = nullptr;
    std::vector<T> filled;  // a broadcast value
    py::array held;
};
template <typename T>
LaneValues<T> readLaneValues(py::handle value, int64_t n, const std::string& arg, const double* range = nullptr);

// A (3, n) output array and its rows.
template <typename T>
struct Output3 {
    py::array_t<T> array;
    T* rows[3] = {};
    explicit Output3(int64_t n);
    // The array in `layout` (see the top of this file).
    py::object shaped(Layout layout) const;
};

// One value per lane: (n,), or a 0-d value for Layout::Single.
py::object shapedLanes(const py::array& values, Layout layout);

// Where readVectors3<float> would read the rows of `value` from (and whether
// it copied): what the tests check the no-copy path with.
py::tuple soaAddresses(py::handle value);

}  // namespace facet::python
