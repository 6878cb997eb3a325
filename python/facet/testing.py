"""Checks for samplers: the chi-square goodness-of-fit test of SPEC 8.

    result = facet.testing.chi2(kernel, wo, samples=200_000, roughness=0.3)
    assert result.passed, result.failure

The kernel draws `samples` directions for `wo` (uniform u from a seeded
NumPy generator); they are binned into cells of the sphere graded toward the
mirror direction (first cells `width` radians wide); each cell's expected
count is N times the pdf integrated over the cell; Pearson's statistic, with
cells expected below 5 pooled, gives the p-value. The sampler passes when
p >= level. `integral` is the pdf's integral over the sphere (1 for a
normalized pdf: a constant factor hardly moves Pearson's statistic, so check
it too). `pdf` replaces the density tested against: another Kernel, or a
callable taking wi (a (3,) float64 array) -- how a test shows that a wrong
pdf fails.

`observed` and `expected` are the two histograms (rings x sectors) with
their cells' `theta_edges` and `phi_edges` (radians), ready to plot.
"""

import collections

import numpy as np

from . import _facet

Chi2Result = collections.namedtuple(
    "Chi2Result",
    "passed statistic dof p_value failure integral unbinned observed expected theta_edges phi_edges",
)


def chi2(kernel, wo, *, samples=200_000, seed=1, width=0.05, level=0.01, tolerance=1e-6, pdf=None,
         equal_area=False, **inputs):
    """The chi-square test of `kernel`'s sampler at direction `wo` (inputs as
    keywords, one value each). width: the first cells' size in radians (about
    alpha / 2 for a lobe of roughness alpha); equal_area=True uses 1/width
    rings by 2/width sectors of equal solid angle instead."""
    wo = np.asarray(wo, dtype=np.float64)
    if wo.shape != (3,):
        raise ValueError(f"chi2(): wo: expected one direction of shape (3,), got {wo.shape}")
    if not isinstance(samples, int) or samples <= 0:
        raise ValueError("chi2(): samples: expected a positive int")
    rng = np.random.default_rng(seed)
    u = rng.random((3, samples), dtype=np.float32)
    wo_lanes = np.ascontiguousarray(np.broadcast_to(wo.astype(np.float32)[:, None], (3, samples)))
    wi, _, _ = kernel.sample(wo_lanes, u, **inputs)
    first_phi = width / 2 if equal_area else min(0.2, width)
    r = _facet._chi2(kernel, wo, np.asarray(wi, dtype=np.float64), inputs, width, first_phi, equal_area, level,
                     tolerance, pdf)
    return Chi2Result(passed=not r["failure"], **r)
