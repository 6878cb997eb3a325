"""facet.testing.chi2: the sampler passes against its own pdf and fails
against a deliberately wrong one (another roughness; a pdf off by a factor)."""

import numpy as np
import pytest

import facet
import facet.testing
from conftest import material

WO = np.array([0.5, 0.1, np.sqrt(1 - 0.26)])


@pytest.fixture(scope="module")
def kernel():
    return facet.compile(material("plastic"))


def test_a_right_sampler_passes(kernel):
    r = facet.testing.chi2(kernel, WO, samples=100_000, width=0.05, roughness=0.5)
    assert r.passed, r.failure
    assert r.p_value > 0.01 and r.dof > 50
    assert abs(r.integral - 1) < 1e-3
    assert r.observed.shape == r.expected.shape == (len(r.theta_edges) - 1, len(r.phi_edges) - 1)
    assert r.observed.sum() == 100_000 - r.unbinned


def test_the_interpreters_sampler_passes():
    k = facet.compile(material("car_paint"), backend="interp")
    r = facet.testing.chi2(k, WO, samples=50_000, width=0.02)
    assert r.passed, r.failure


def test_a_wrong_pdf_fails(kernel):
    rougher = facet.compile(material("plastic"), set={"roughness": 0.6})
    r = facet.testing.chi2(kernel, WO, samples=100_000, width=0.05, pdf=rougher, roughness=0.5)
    assert not r.passed and r.p_value < 1e-6


def test_a_pdf_off_by_a_factor_fails(kernel):
    r = facet.testing.chi2(kernel, WO, samples=100_000, width=0.1, equal_area=True, tolerance=1e-4,
                           pdf=lambda wi: 1.05 * float(kernel.pdf(wi, WO, roughness=0.5)), roughness=0.5)
    assert not r.passed
    assert abs(r.integral - 1.05) < 1e-2


def test_bad_arguments(kernel):
    with pytest.raises(ValueError, match="wo"):
        facet.testing.chi2(kernel, [0, 0, 1, 0])
    with pytest.raises(ValueError, match="above the surface"):
        facet.testing.chi2(kernel, [0, 0, -1])
    with pytest.raises(TypeError, match="pdf"):
        facet.testing.chi2(kernel, WO, samples=100, pdf=3)
