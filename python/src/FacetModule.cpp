// FacetModule: the extension module facet._facet. The Python package
// (python/facet/__init__.py) builds the user-facing API on it: compile()
// and check() with their errors, and the Kernel class bound here.
//
// One Compiler per process, created on first use and shared by every
// kernel (as the C API does): one JIT, one kernel cache (FACET_CACHE_DIR,
// $XDG_CACHE_HOME/facet or ~/.cache/facet, trusted as Kernel.h says). Each
// kernel holds the Compiler alive, since its code lives in that JIT.
#include "PyArrays.h"
#include "PyKernel.h"
#include "PyTesting.h"

#include "Checker.h"
#include "Diagnostics.h"

#include <pybind11/stl.h>

#include <mutex>

namespace py = pybind11;
using namespace facet;
using facet::python::PyKernel;

namespace {

std::shared_ptr<Compiler> sharedCompiler() {
    static std::shared_ptr<Compiler> compiler = std::make_shared<Compiler>();  // thread-safe initialization
    return compiler;
}

py::list diagnosticTuples(const DiagnosticEngine& diags) {
    py::list out;
    for (const Diagnostic& d : diags.diagnostics())
        out.append(py::make_tuple(d.loc.file ? *d.loc.file : std::string(), d.loc.line, d.loc.col, d.message));
    return out;
}

// (kernel, [], "") on success; (None, diagnostics, "") for a material error;
// (None, [], message) for bad options. Internal errors raise RuntimeError.
py::tuple compile(std::optional<std::string> path, std::optional<std::string> text, const std::string& name,
                  const std::string& options) {
    CompileOptions parsed;
    std::string problem = CompileOptions::parse(options, parsed);
    if (!problem.empty()) return py::make_tuple(py::none(), py::list(), problem);
    std::shared_ptr<Compiler> compiler = sharedCompiler();
    DiagnosticEngine diags;
    std::unique_ptr<Kernel> kernel;
    {
        py::gil_scoped_release release;
        kernel = text ? compiler->compileText(*text, path ? *path : "<text>", name, parsed, diags)
                      : compiler->compileFile(*path, name, parsed, diags);
    }
    if (!kernel) return py::make_tuple(py::none(), diagnosticTuples(diags), "");
    auto wrapped = std::make_unique<PyKernel>(compiler, std::move(kernel), parsed.canonical());
    return py::make_tuple(py::cast(std::move(wrapped)), py::list(), "");
}

// The diagnostics of checking a file or a text (every material in it).
py::list check(std::optional<std::string> path, std::optional<std::string> text) {
    DiagnosticEngine diags;
    {
        py::gil_scoped_release release;
        if (text)
            loadProgramText(*text, path ? *path : "<text>", diags);
        else
            loadProgramFile(*path, diags);
    }
    return diagnosticTuples(diags);
}

py::dict optionsOf(const PyKernel& k) {
    py::dict d;
    const Kernel& kernel = k.kernel();
    d["backend"] = backendName(kernel.backend());
    d["width"] = kernel.width();
    d["variant"] = kernel.variant();
    d["canonical"] = k.options();
    return d;
}

}  // namespace

PYBIND11_MODULE(_facet, m) {
    m.doc() = "Facet's compiler and kernels (use the facet package, not this module)";
    // Internal errors (bugs in Facet) surface as RuntimeError with their text.
    py::register_exception<InternalError>(m, "InternalError", PyExc_RuntimeError);

    py::class_<PyKernel>(m, "Kernel")
        .def("eval", [](const PyKernel& k, py::handle wi, py::handle wo, bool status, py::kwargs inputs) {
                 return k.eval(wi, wo, inputs, status);
             }, py::arg("wi"), py::arg("wo"), py::kw_only(), py::arg("status") = false)
        .def("sample", [](const PyKernel& k, py::handle wo, py::handle u, bool status, py::kwargs inputs) {
                 return k.sample(wo, u, inputs, status);
             }, py::arg("wo"), py::arg("u"), py::kw_only(), py::arg("status") = false)
        .def("pdf", [](const PyKernel& k, py::handle wi, py::handle wo, bool status, py::kwargs inputs) {
                 return k.pdf(wi, wo, inputs, status);
             }, py::arg("wi"), py::arg("wo"), py::kw_only(), py::arg("status") = false)
        .def_property_readonly("_inputs", &PyKernel::inputs)
        .def_property_readonly("options", &optionsOf)
        .def_property_readonly("backend", [](const PyKernel& k) { return backendName(k.kernel().backend()); })
        .def_property_readonly("width", [](const PyKernel& k) { return k.kernel().width(); })
        .def_property_readonly("variant", [](const PyKernel& k) { return k.kernel().variant(); })
        .def_property_readonly("origin", [](const PyKernel& k) { return k.kernel().origin(); })
        .def_property_readonly("material", [](const PyKernel& k) { return k.kernel().material().name; })
        .def_property_readonly("code_tier", [](const PyKernel& k) { return k.kernel().codeTier(); })
        .def_property_readonly("sampler", [](const PyKernel& k) {
            py::gil_scoped_release release;  // the first call compiles the sampler
            return k.kernel().samplerTier();
        })
        .def("__repr__", [](const PyKernel& k) {
            const Kernel& kernel = k.kernel();
            return "<facet.Kernel " + kernel.material().name + ": " + backendName(kernel.backend()) +
                   (kernel.width() > 1 ? " width " + std::to_string(kernel.width()) : std::string()) + ", " +
                   kernel.variant() + ">";
        })
        .def("wait_optimized", [](const PyKernel& k) {
            py::gil_scoped_release release;
            k.kernel().waitOptimized();
        });

    m.def("compile", &compile, py::arg("path"), py::arg("text"), py::arg("name"), py::arg("options"));
    m.def("check", &check, py::arg("path"), py::arg("text"));
    m.def("_chi2", &facet::python::chi2, py::arg("kernel"), py::arg("wo"), py::arg("wi"), py::arg("inputs"),
          py::arg("first_theta"), py::arg("first_phi"), py::arg("equal_area"), py::arg("level"), py::arg("tolerance"),
          py::arg("pdf"));
    m.def("_time_eval_batch", &facet::python::timeEvalBatch, py::arg("kernel"), py::arg("wi"), py::arg("wo"),
          py::arg("calls"),
          "Seconds per Kernel::evalBatch call (what facet_eval_batch forwards to) on (3, N) float32 arrays, "
          "timed in C++ with the defaults of every input: the baseline of the binding's call overhead");
    m.def("_soa_addresses", &facet::python::soaAddresses,
          "Where eval would read the rows of a direction array from, and whether it converted it (tests)");
}
