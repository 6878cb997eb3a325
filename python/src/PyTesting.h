// PyTesting: facet._chi2, the chi-square test behind facet.testing.chi2
// (PyTesting.cpp says how it bins and integrates).
#pragma once

#include "PyKernel.h"

namespace facet::python {

// The test of `wi` (samples the kernel drew for `wo` at `inputs`) against
// the kernel's pdf (or `pdf`: another Kernel or a callable), on cells graded
// from firstTheta x firstPhi at the mirror direction (or equal-area cells,
// 1/firstTheta rings by 1/firstPhi sectors). Returns statistic, dof,
// p_value, failure ("" when the sampler passes at `level`), integral (of
// the pdf over the sphere), unbinned (samples with no direction), and the
// observed and expected counts per cell with the cells' edges.
py::dict chi2(const PyKernel& kernel, py::handle wo, py::handle wi, py::dict inputs, double firstTheta,
              double firstPhi, bool equalArea, double level, double tolerance, py::object pdf);

// Seconds per call of the kernel's batch entry (Kernel::evalBatch) on wi,
// wo ((3, N) float32), the median of 5 rounds of calls/5 calls, with the
// GIL released: the library's own cost, next to which the Python call's
// is measured (examples/python/call_overhead.py).
double timeEvalBatch(const PyKernel& kernel, py::handle wi, py::handle wo, int calls);

}  // namespace facet::python
