// PyArrays: reading NumPy arrays as SoA rows and shaping the results
// (PyArrays.h has the conventions).
#include "PyArrays.h"

#include <fmt/format.h>

namespace facet::python {

namespace {

std::string shapeText(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// `value` as an array of real numbers (ints and floats; not bool, complex,
// strings or objects).
py::array numericArray(py::handle value, const std::string& arg) {
    py::array a = py::array::ensure(value);
    if (!a) throw py::type_error(fmt::format("{}: expected an array of numbers", arg));
    char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::type_error(
            fmt::format("{}: expected real numbers, got an array of dtype {}", arg, std::string(py::str(a.dtype()))));
    return a;
}

// Imported once and never released: a static py::object would be released
// at exit, after the interpreter is gone.
py::module_& numpy() {
    static py::module_* np = new py::module_(py::module_::import("numpy"));
    return *np;
}

template <typename T>
bool usableInPlace(const py::array& a) {
    return a.dtype().is(py::dtype::of<T>()) && (a.flags() & py::array::c_style);
}

}  // namespace

template <typename T>
Vectors3<T> readVectors3(py::handle value, const char* arg) {
    py::array a = numericArray(value, arg);
    Vectors3<T> v;
    py::array soa;  // (3, n) before conversion
    if (a.ndim() == 1 && a.shape(0) == 3) {
        v.layout = Layout::Single;
        v.n = 1;
        soa = a.attr("reshape")(3, 1);
    } else if (a.ndim() == 2 && a.shape(1) == 3) {
        v.layout = Layout::RowsOfThree;  // (N, 3), (3, 3) included
        v.n = a.shape(0);
        soa = a.attr("T");
    } else if (a.ndim() == 2 && a.shape(0) == 3) {
        v.layout = Layout::ThreeRows;
        v.n = a.shape(1);
        soa = a;
    } else {
        throw py::value_error(fmt::format("{}: expected shape (N, 3), (3, N) or (3,), got {}", arg, shapeText(a)));
    }
    if (!usableInPlace<T>(soa)) {
        soa = numpy().attr("ascontiguousarray")(soa, py::dtype::of<T>());
        v.copied = true;
    }
    const T* data = static_cast<const T*>(soa.data());
    for (int k = 0; k < 3; ++k) v.rows[k] = data + k * v.n;
    v.held = soa;
    return v;
}

template <typename T>
void matchLanes(Vectors3<T>& v, int64_t n, const char* arg, const char* other) {
    if (v.n == n) return;
    if (v.n == 1) {
        // One vector for every lane: a (3, n) broadcast copy.
        py::array_t<T> wide({py::ssize_t(3), py::ssize_t(n)});
        T* out = wide.mutable_data();
        for (int k = 0; k < 3; ++k) {
            T x = v.rows[k][0];
            for (int64_t i = 0; i < n; ++i) out[k * n + i] = x;
            v.rows[k] = out + k * n;
        }
        v.held = wide;
        v.n = n;
        return;
    }
    throw py::value_error(fmt::format("{}: {} vectors, but {} has {}", arg, v.n, other, n));
}

template <typename T>
LaneValues<T> readLaneValues(py::handle value, int64_t n, const std::string& arg, const double* range) {
    py::array a = numericArray(value, arg);
    LaneValues<T> v;
    // In [lo, hi] as double; NaN stays NaN (the kernel reports the lane).
    auto clamped = [&](double x) { return range && x < range[0] ? range[0] : range && x > range[1] ? range[1] : x; };
    if (a.ndim() == 0 || (a.ndim() == 1 && a.shape(0) == 1 && n != 1)) {
        double x = py::array_t<double, py::array::forcecast>(a.attr("reshape")(1)).at(0);
        v.filled.assign(size_t(n), T(clamped(x)));
        v.data = v.filled.data();
        return v;
    }
    if (a.ndim() != 1 || a.shape(0) != n)
        throw py::value_error(fmt::format("{}: expected a number or {} values (one per lane), got shape {}", arg, n,
                                          shapeText(a)));
    if (range && !a.dtype().is(py::dtype::of<T>())) {
        py::array_t<double, py::array::forcecast> d(a);
        v.filled.resize(size_t(n));
        for (int64_t i = 0; i < n; ++i) v.filled[size_t(i)] = T(clamped(d.at(i)));
        v.data = v.filled.data();
        return v;
    }
    if (!usableInPlace<T>(a)) a = numpy().attr("ascontiguousarray")(a, py::dtype::of<T>());
    v.data = static_cast<const T*>(a.data());
    v.held = a;
    return v;
}

template <typename T>
Output3<T>::Output3(int64_t n) : array({py::ssize_t(3), py::ssize_t(n)}) {
    T* data = array.mutable_data();
    for (int k = 0; k < 3; ++k) rows[k] = data + k * n;
}

template <typename T>
py::object Output3<T>::shaped(Layout layout) const {
    switch (layout) {
        case Layout::Single: return array.attr("reshape")(3);
        case Layout::RowsOfThree: return array.attr("T");
        case Layout::ThreeRows: break;
    }
    return array;
}

py::object shapedLanes(const py::array& values, Layout layout) {
    if (layout == Layout::Single) return values.attr("reshape")(py::tuple());
    return values;
}

py::tuple soaAddresses(py::handle value) {
    Vectors3<float> v = readVectors3<float>(value, "value");
    return py::make_tuple(reinterpret_cast<uintptr_t>(v.rows[0]), reinterpret_cast<uintptr_t>(v.rows[1]),
                          reinterpret_cast<uintptr_t>(v.rows[2]), v.copied);
}

#define FACET_ARRAYS_FOR(T)                                                                       \
    template Vectors3<T> readVectors3<T>(py::handle, const char*);                               \
    template void matchLanes<T>(Vectors3<T>&, int64_t, const char*, const char*);                 \
    template LaneValues<T> readLaneValues<T>(py::handle, int64_t, const std::string&, const double*); \
    template struct Output3<T>;
FACET_ARRAYS_FOR(float)
FACET_ARRAYS_FOR(double)
#undef FACET_ARRAYS_FOR

}  // namespace facet::python
