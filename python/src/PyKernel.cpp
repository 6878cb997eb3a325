// PyKernel: the batch calls of facet.Kernel over the C++ Kernel, and the
// interpreter's float64 path (PyKernel.h).
#include "PyKernel.h"

#include "Sampling.h"

#include <fmt/format.h>

#include <cmath>

namespace facet::python {

namespace {

// Two vector arguments of one call, broadcast to a common lane count (a
// single vector, or a batch of one, stands for every lane). Results take the
// first argument's layout unless it is a single vector.
template <typename T>
struct VectorPair {
    Vectors3<T> a, b;
    int64_t n = 0;
    Layout layout = Layout::Single;
};

template <typename T>
VectorPair<T> readPair(py::handle x, const char* xName, py::handle y, const char* yName) {
    VectorPair<T> p{readVectors3<T>(x, xName), readVectors3<T>(y, yName)};
    p.n = std::max(p.a.n, p.b.n);
    if (p.a.n == 0 || p.b.n == 0) p.n = 0;
    p.layout = p.a.layout != Layout::Single ? p.a.layout : p.b.layout;
    matchLanes(p.a, p.n, xName, yName);
    matchLanes(p.b, p.n, yName, xName);
    return p;
}

template <typename T>
void gather(const Vectors3<T>& v, int64_t i, double out[3]) {
    for (int k = 0; k < 3; ++k) out[k] = double(v.rows[k][i]);
}

// fn(i, a, b, slots) for every lane of an interpreter call, with the GIL
// released: lane i's two vectors and its slot values (null when the
// material has none), in double.
template <typename Columns, typename Fn>
void forEachLane(const VectorPair<double>& d, const Columns& in, Fn fn) {
    py::gil_scoped_release release;
    std::vector<double> slots(in.slots.size());
    for (int64_t i = 0; i < d.n; ++i) {
        double a[3], b[3];
        gather(d.a, i, a);
        gather(d.b, i, b);
        in.lane(i, slots);
        fn(i, a, b, slots.empty() ? nullptr : slots.data());
    }
}

}  // namespace

template <typename T>
struct PyKernel::InputColumns {
    // One pointer per slot, as the kernels take them; null for an input not
    // given, which the kernels read as its default (facet.h) -- no column of
    // n copies of it to fill.
    std::vector<const T*> slots;
    std::vector<double> defaults;          // per slot
    std::vector<LaneValues<T>> values;     // what the pointers point into
    std::vector<Vectors3<T>> vectors;
    // The slot values of lane i (interpreter path).
    void lane(int64_t i, std::vector<double>& out) const {
        for (size_t s = 0; s < slots.size(); ++s) out[s] = slots[s] ? double(slots[s][i]) : defaults[s];
    }
};

PyKernel::PyKernel(std::shared_ptr<Compiler> compiler, std::unique_ptr<Kernel> kernel, std::string options)
    : compiler_(std::move(compiler)), kernel_(std::move(kernel)), options_(std::move(options)) {
    if (kernel_->backend() == Backend::Interp) {
        interp_.emplace(kernel_->material(), kernel_->lobeEnergyTables());
        interp_->setTransport(kernel_->transport());
    }
}

template <typename T>
PyKernel::InputColumns<T> PyKernel::readInputs(const py::dict& given, int64_t n, const char* call) const {
    const CheckedMaterial& m = kernel_->material();
    InputColumns<T> in;
    in.slots.assign(size_t(m.slotCount), nullptr);
    in.defaults.assign(size_t(m.slotCount), 0.0);
    for (const CheckedInput& input : m.inputs)
        for (int k = 0; k < input.slotCount(); ++k)
            in.defaults[size_t(input.firstSlot + k)] = input.defaultValue[size_t(k)];
    size_t used = 0;
    // Inputs not given stay null slots: a call that gives none reads nothing here.
    for (const CheckedInput& input : m.inputs) {
        if (given.empty()) break;
        py::str key(input.name);
        if (!given.contains(key)) continue;
        ++used;
        std::string arg = fmt::format("{}(): input '{}'", call, input.name);
        if (input.type == ValueType::Rgb) {
            Vectors3<T> v = readVectors3<T>(given[key], arg.c_str());
            matchLanes(v, n, arg.c_str(), "the directions");
            for (int k = 0; k < 3; ++k) in.slots[size_t(input.firstSlot + k)] = v.rows[k];
            in.vectors.push_back(std::move(v));
        } else {
            double range[2] = {input.lo, input.hi};
            LaneValues<T> v = readLaneValues<T>(given[key], n, arg, input.hasRange ? range : nullptr);
            in.slots[size_t(input.firstSlot)] = v.data;
            in.values.push_back(std::move(v));
        }
    }
    if (used != given.size()) {
        std::string names;
        for (const CheckedInput& input : m.inputs) names += (names.empty() ? "" : ", ") + input.name;
        for (auto item : given) {
            std::string name = py::str(item.first);
            bool known = false;
            for (const CheckedInput& input : m.inputs) known |= input.name == name;
            if (!known)
                throw py::type_error(fmt::format("{}(): the material has no input '{}' (its inputs: {})", call, name,
                                                 names.empty() ? "none" : names));
        }
    }
    return in;
}

py::object PyKernel::eval(py::handle wi, py::handle wo, py::dict inputs, bool status) const {
    return interp_ ? evalInterpreted(wi, wo, inputs, status) : evalCompiled(wi, wo, inputs, status);
}
py::object PyKernel::sample(py::handle wo, py::handle u, py::dict inputs, bool status) const {
    return interp_ ? sampleInterpreted(wo, u, inputs, status) : sampleCompiled(wo, u, inputs, status);
}
py::object PyKernel::pdf(py::handle wi, py::handle wo, py::dict inputs, bool status) const {
    return interp_ ? pdfInterpreted(wi, wo, inputs, status) : pdfCompiled(wi, wo, inputs, status);
}

py::object PyKernel::evalCompiled(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const {
    VectorPair<float> d = readPair<float>(wi, "wi", wo, "wo");
    InputColumns<float> in = readInputs<float>(inputs, d.n, "eval");
    Output3<float> rgb(d.n);
    py::array_t<bool> invalid(status ? d.n : 0);
    uint8_t* flags = status ? reinterpret_cast<uint8_t*>(invalid.mutable_data()) : nullptr;
    {
        py::gil_scoped_release release;
        kernel_->evalBatch(d.n, d.a.rows, d.b.rows, in.slots.data(), rgb.rows, flags);
    }
    if (!status) return rgb.shaped(d.layout);
    return py::make_tuple(rgb.shaped(d.layout), shapedLanes(invalid, d.layout));
}

py::object PyKernel::evalInterpreted(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const {
    VectorPair<double> d = readPair<double>(wi, "wi", wo, "wo");
    InputColumns<double> in = readInputs<double>(inputs, d.n, "eval");
    Output3<double> rgb(d.n);
    py::array_t<bool> invalid(d.n);
    bool* flags = invalid.mutable_data();
    forEachLane(d, in, [&](int64_t i, const double* a, const double* b, const double* slots) {
        EvalResult<double> r = interp_->eval(a, b, slots);
        bool bad = !r.valid;
        for (double c : r.rgb) bad |= !std::isfinite(c);
        for (int k = 0; k < 3; ++k) rgb.rows[k][i] = bad ? 0.0 : r.rgb[size_t(k)];
        flags[i] = bad;
    });
    if (!status) return rgb.shaped(d.layout);
    return py::make_tuple(rgb.shaped(d.layout), shapedLanes(invalid, d.layout));
}

py::object PyKernel::sampleCompiled(py::handle wo, py::handle u, const py::dict& inputs, bool status) const {
    VectorPair<float> d = readPair<float>(wo, "wo", u, "u");
    InputColumns<float> in = readInputs<float>(inputs, d.n, "sample");
    Output3<float> wi(d.n), weight(d.n);
    py::array_t<float> pdf(d.n);
    int64_t bad;
    {
        py::gil_scoped_release release;
        bad = kernel_->sampleBatch(d.n, d.a.rows, d.b.rows, in.slots.data(), wi.rows, pdf.mutable_data(),
                                   weight.rows);
    }
    py::tuple out = py::make_tuple(wi.shaped(d.layout), shapedLanes(pdf, d.layout), weight.shaped(d.layout));
    return status ? py::make_tuple(out[0], out[1], out[2], bad) : py::object(out);
}

py::object PyKernel::sampleInterpreted(py::handle wo, py::handle u, const py::dict& inputs, bool status) const {
    VectorPair<double> d = readPair<double>(wo, "wo", u, "u");
    InputColumns<double> in = readInputs<double>(inputs, d.n, "sample");
    Output3<double> wi(d.n), weight(d.n);
    py::array_t<double> pdf(d.n);
    double* p = pdf.mutable_data();
    int64_t bad = 0;
    forEachLane(d, in, [&](int64_t i, const double* o, const double* u, const double* slots) {
        SampleResult<double> r = interp_->sample(o, u, slots);
        bool invalid = !r.valid || !std::isfinite(r.pdf);
        for (double c : r.weight) invalid |= !std::isfinite(c);
        bad += invalid;
        double w[3] = {r.wi.x, r.wi.y, r.wi.z};
        for (int k = 0; k < 3; ++k) {
            wi.rows[k][i] = invalid ? 0.0 : w[k];
            weight.rows[k][i] = invalid || !(r.pdf > 0) ? 0.0 : r.weight[size_t(k)];
        }
        p[i] = invalid ? 0.0 : r.pdf;
    });
    py::tuple out = py::make_tuple(wi.shaped(d.layout), shapedLanes(pdf, d.layout), weight.shaped(d.layout));
    return status ? py::make_tuple(out[0], out[1], out[2], bad) : py::object(out);
}

py::object PyKernel::pdfCompiled(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const {
    VectorPair<float> d = readPair<float>(wi, "wi", wo, "wo");
    InputColumns<float> in = readInputs<float>(inputs, d.n, "pdf");
    py::array_t<float> pdf(d.n);
    int64_t bad;
    {
        py::gil_scoped_release release;
        bad = kernel_->pdfBatch(d.n, d.a.rows, d.b.rows, in.slots.data(), pdf.mutable_data());
    }
    py::object out = shapedLanes(pdf, d.layout);
    return status ? py::object(py::make_tuple(out, bad)) : out;
}

py::object PyKernel::pdfInterpreted(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const {
    VectorPair<double> d = readPair<double>(wi, "wi", wo, "wo");
    InputColumns<double> in = readInputs<double>(inputs, d.n, "pdf");
    py::array_t<double> pdf(d.n);
    double* p = pdf.mutable_data();
    int64_t bad = 0;
    forEachLane(d, in, [&](int64_t i, const double* a, const double* b, const double* slots) {
        PdfResult<double> r = interp_->pdf(a, b, slots);
        bool invalid = !r.valid || !std::isfinite(r.pdf);
        bad += invalid;
        p[i] = invalid ? 0.0 : r.pdf;
    });
    py::object out = shapedLanes(pdf, d.layout);
    return status ? py::object(py::make_tuple(out, bad)) : out;
}

double PyKernel::pdfAt(const double wi[3], const double wo[3], const std::vector<double>& slots) const {
    if (interp_) {
        PdfResult<double> r = interp_->pdf(wi, wo, slots.empty() ? nullptr : slots.data());
        return r.valid && std::isfinite(r.pdf) ? r.pdf : 0.0;
    }
    float a[3], b[3];
    for (int k = 0; k < 3; ++k) a[k] = float(wi[k]), b[k] = float(wo[k]);
    std::vector<float> s(slots.begin(), slots.end());
    return kernel_->pdf(a, b, s.empty() ? nullptr : s.data());
}

std::vector<double> PyKernel::slotValues(const py::dict& inputs, const char* call) const {
    InputColumns<double> in = readInputs<double>(inputs, 1, call);
    std::vector<double> slots(in.slots.size());
    in.lane(0, slots);
    return slots;
}

py::list PyKernel::inputs() const {
    py::list out;
    for (const CheckedInput& input : kernel_->material().inputs) {
        bool rgb = input.type == ValueType::Rgb;
        py::object def = rgb ? py::object(py::make_tuple(input.defaultValue[0], input.defaultValue[1],
                                                         input.defaultValue[2]))
                             : py::object(py::float_(input.defaultValue[0]));
        py::object range = input.hasRange ? py::object(py::make_tuple(input.lo, input.hi)) : py::object(py::none());
        out.append(py::make_tuple(input.name, rgb ? "rgb" : "float", def, range));
    }
    return out;
}

}  // namespace facet::python
