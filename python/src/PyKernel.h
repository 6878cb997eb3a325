// PyKernel: a compiled material as the Python `facet.Kernel`: eval, sample
// and pdf over NumPy arrays (PyArrays.h), the material's inputs by keyword,
// and what the kernel is (backend, width, variant, sampler).
//
// Compiled backends (scalar, simd) compute in float32 through the kernel's
// batch entry points, exactly as the C API's facet_*_batch calls do (the
// same Kernel methods). backend="interp" evaluates the double reference
// interpreter lane by lane and returns float64: directions and inputs given
// as float64 are used as they are, not rounded to float first.
//
// Every batch call converts its arguments with the GIL held and runs the
// kernel with it released, so Python threads calling one kernel run at once
// (a Kernel is immutable and thread-safe).
#pragma once

#include "PyArrays.h"

#include "Interpreter.h"
#include "Kernel.h"

#include <memory>
#include <optional>
#include <string>

namespace facet::python {

class PyKernel {
public:
    PyKernel(std::shared_ptr<Compiler> compiler, std::unique_ptr<Kernel> kernel, std::string options);

    // The values, and with `status` a second result: per-lane invalid flags
    // (bool) for eval, the number of invalid lanes for sample and pdf.
    py::object eval(py::handle wi, py::handle wo, py::dict inputs, bool status) const;
    py::object sample(py::handle wo, py::handle u, py::dict inputs, bool status) const;
    py::object pdf(py::handle wi, py::handle wo, py::dict inputs, bool status) const;

    // The density at one pair of directions for the material at one point
    // (`inputs` as given to pdf(), scalars), in double: what the chi-square
    // helper integrates over its cells. Slot values from slotValues().
    double pdfAt(const double wi[3], const double wo[3], const std::vector<double>& slots) const;
    std::vector<double> slotValues(const py::dict& inputs, const char* call) const;

    // (name, type, default, (lo, hi) or None) per input, in slot order.
    py::list inputs() const;
    const Kernel& kernel() const { return *kernel_; }
    const std::string& options() const { return options_; }
    bool interpreted() const { return interp_.has_value(); }

private:
    template <typename T>
    struct InputColumns;
    template <typename T>
    InputColumns<T> readInputs(const py::dict& given, int64_t n, const char* call) const;

    py::object evalCompiled(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const;
    py::object evalInterpreted(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const;
    py::object sampleCompiled(py::handle wo, py::handle u, const py::dict& inputs, bool status) const;
    py::object sampleInterpreted(py::handle wo, py::handle u, const py::dict& inputs, bool status) const;
    py::object pdfCompiled(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const;
    py::object pdfInterpreted(py::handle wi, py::handle wo, const py::dict& inputs, bool status) const;

    std::shared_ptr<Compiler> compiler_;  // owns the JIT the kernel's code lives in
    std::unique_ptr<Kernel> kernel_;
    std::string options_;                 // the options as compiled (CompileOptions::canonical)
    std::optional<Interpreter<double>> interp_;  // backend=interp: the double reference
};

}  // namespace facet::python
