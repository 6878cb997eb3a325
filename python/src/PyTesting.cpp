// PyTesting: the chi-square goodness-of-fit test of SPEC 8 for Python users,
// facet._chi2 (facet.testing.chi2 draws the samples and calls it), on the
// same machinery as Facet's own sampling tests (apps/verify/ChiSquare.h):
// cells graded toward the lobe, each cell's probability integrated from the
// pdf, Pearson's statistic with small cells pooled, and the pdf's integral
// over the sphere (the normalization check).
#include "PyTesting.h"

#include "ChiSquare.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace facet::python {

py::dict chi2(const PyKernel& kernel, py::handle wo, py::handle wi, py::dict inputs, double firstTheta,
              double firstPhi, bool equalArea, double level, double tolerance, py::object pdf) {
    Vectors3<double> o = readVectors3<double>(wo, "wo");
    if (o.n != 1) throw py::value_error("chi2(): wo: expected one direction");
    Vec3<double> out{o.rows[0][0], o.rows[1][0], o.rows[2][0]};
    double len = std::sqrt(out.x * out.x + out.y * out.y + out.z * out.z);
    if (!(len > 0.999 && len < 1.001) || !(out.z > 0))
        throw py::value_error("chi2(): wo: expected a unit direction above the surface (z > 0)");
    Vectors3<double> samples = readVectors3<double>(wi, "wi");
    if (!(firstTheta > 0) || !(firstPhi > 0) || !(tolerance > 0) || !(level > 0 && level < 1))
        throw py::value_error("chi2(): the cell widths and the tolerance must be positive and the level in (0, 1)");
    std::vector<double> slots = kernel.slotValues(inputs, "chi2");

    double theta = std::atan2(std::hypot(out.x, out.y), out.z), phi = std::atan2(-out.y, -out.x);
    SphereGrid grid = equalArea ? SphereGrid::equalArea(int(std::lround(1 / firstTheta)), int(std::lround(1 / firstPhi)))
                                : SphereGrid::forLobe(theta, theta, phi, firstTheta, firstPhi);
    CellHistogram binned(grid);
    for (int64_t i = 0; i < samples.n; ++i) binned.add(grid, {samples.rows[0][i], samples.rows[1][i], samples.rows[2][i]});
    // The density: the kernel's own, another kernel's, or a Python callable
    // taking wi as a (3,) float64 array (the deliberately wrong pdfs of tests).
    const PyKernel* other = pdf.is_none() ? &kernel : py::isinstance<PyKernel>(pdf) ? &pdf.cast<const PyKernel&>() : nullptr;
    if (!other && !PyCallable_Check(pdf.ptr()))
        throw py::type_error("chi2(): pdf: expected None, a Kernel or a callable taking wi");
    double wo3[3] = {out.x, out.y, out.z};
    PdfFunction density = [&](const Vec3<double>& w) {
        double a[3] = {w.x, w.y, w.z};
        if (other) return other->pdfAt(a, wo3, slots);
        py::array_t<double> arg(3);
        std::copy(a, a + 3, arg.mutable_data());
        return pdf(arg).cast<double>();
    };
    FitOutcome fit = fitToPdf(grid, binned, density, FitSettings{tolerance, level});
    const Chi2Outcome& outcome = fit.chi2;
    const std::vector<double>& observed = binned.observed;
    const std::vector<double>& expected = fit.expected;

    py::dict result;
    result["statistic"] = outcome.statistic;
    result["dof"] = outcome.dof;
    result["p_value"] = outcome.pValue;
    result["failure"] = outcome.failure;
    result["integral"] = fit.integral;
    result["unbinned"] = binned.unbinned;
    py::array_t<double> obs({grid.rings(), grid.sectors()}), exp({grid.rings(), grid.sectors()});
    std::copy(observed.begin(), observed.end(), obs.mutable_data());
    std::copy(expected.begin(), expected.end(), exp.mutable_data());
    result["observed"] = obs;
    result["expected"] = exp;
    result["theta_edges"] = py::array_t<double>(py::ssize_t(grid.thetaEdges().size()), grid.thetaEdges().data());
    result["phi_edges"] = py::array_t<double>(py::ssize_t(grid.phiEdges().size()), grid.phiEdges().data());
    return result;
}

double timeEvalBatch(const PyKernel& kernel, py::handle wi, py::handle wo, int calls) {
    Vectors3<float> a = readVectors3<float>(wi, "wi"), b = readVectors3<float>(wo, "wo");
    if (a.n != b.n || calls <= 0) throw py::value_error("_time_eval_batch(): wi and wo of one length, calls > 0");
    if (kernel.interpreted()) throw py::value_error("_time_eval_batch(): a compiled kernel");
    std::vector<const float*> slots(size_t(kernel.kernel().material().slotCount), nullptr);  // the defaults
    std::vector<float> out(size_t(3 * a.n));
    float* rows[3] = {out.data(), out.data() + a.n, out.data() + 2 * a.n};
    std::vector<double> rounds;
    py::gil_scoped_release release;
    for (int r = 0; r < 5; ++r) {
        auto start = std::chrono::steady_clock::now();
        int each = std::max(1, calls / 5);
        for (int c = 0; c < each; ++c) kernel.kernel().evalBatch(a.n, a.rows, b.rows, slots.data(), rows);
        rounds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / each);
    }
    std::sort(rounds.begin(), rounds.end());
    return rounds[2];
}

}  // namespace facet::python
