"""The package computes what the C API computes: the same bits for eval,
sample and pdf on the same float32 inputs, on every backend, SIMD width and
math mode (backend="interp": the package's float64 values rounded to float32
are the C API's)."""

import numpy as np
import pytest

import facet
from conftest import material, directions

BACKENDS = ["backend=interp", "backend=scalar", "backend=simd;width=4", "backend=simd;width=8",
            "backend=simd;width=16"]
MATHS = ["math=exact", "math=fast"]
MATERIALS = ["plastic", "car_paint", "brushed_metal"]


def keywords(options):
    out = {}
    for item in options.split(";"):
        key, value = item.split("=")
        out[key] = int(value) if key == "width" else value
    return out


def lane_inputs(kernel, rng, n):
    """Per-lane values for every input (rgb as (n, 3)) and the C API's slot columns."""
    given, slots = {}, []
    for inp in kernel.inputs:
        if inp.type == "rgb":
            v = rng.uniform(0.05, 0.95, size=(n, 3)).astype(np.float32)
            given[inp.name] = v
            slots += [np.ascontiguousarray(v[:, c]) for c in range(3)]
        else:
            lo, hi = inp.range or (0.0, 1.0)
            v = rng.uniform(lo, hi, size=n).astype(np.float32)
            given[inp.name] = v
            slots.append(v)
    return given, slots


@pytest.mark.parametrize("name", MATERIALS)
@pytest.mark.parametrize("math", MATHS)
@pytest.mark.parametrize("backend", BACKENDS)
def test_same_bits_as_the_c_api(capi, rng, name, backend, math):
    if backend == "backend=interp" and math == "math=fast":
        pytest.skip("the interpreter has no fast mode")
    options = f"{backend};{math}"
    n = 333  # not a multiple of any width: the tail lanes too
    kernel = facet.compile(material(name), **keywords(options))
    c = capi.compile(material(name), options)
    try:
        wi = np.ascontiguousarray(directions(rng, n).T, dtype=np.float32)
        wo = np.ascontiguousarray(directions(rng, n).T, dtype=np.float32)
        wi[:, 7] = np.nan  # an invalid lane, reported by both
        u = rng.random((3, n), dtype=np.float32)
        given, slots = lane_inputs(kernel, rng, n)

        rgb, invalid = kernel.eval(wi, wo, status=True, **given)
        c_rgb, c_status, c_bad = capi.eval(c, wi, wo, slots)
        assert np.array_equal(np.float32(rgb), c_rgb)
        assert np.array_equal(invalid, c_status.astype(bool))
        assert invalid.sum() == c_bad >= 1 and invalid[7]

        s_wi, s_pdf, s_weight, bad = kernel.sample(wo, u, status=True, **given)
        c_wi, c_pdf, c_weight, c_bad = capi.sample(c, wo, u, slots)
        assert np.array_equal(np.float32(s_wi), c_wi)
        assert np.array_equal(np.float32(s_pdf), c_pdf)
        assert np.array_equal(np.float32(s_weight), c_weight)
        assert bad == c_bad

        pdf, bad = kernel.pdf(wi, wo, status=True, **given)
        c_pdf, c_bad = capi.pdf(c, wi, wo, slots)
        assert np.array_equal(np.float32(pdf), c_pdf)
        assert bad == c_bad >= 1
        assert (rgb.dtype, pdf.dtype) == ((np.float64, np.float64) if "interp" in backend else (np.float32, np.float32))
    finally:
        capi.release(c)


def test_interp_uses_float64_inputs_as_given(rng):
    """float64 directions reach the reference unrounded: its values differ from
    those at the float32-rounded directions (by about float's rounding)."""
    k = facet.compile(material("plastic"), backend="interp")
    wi, wo = directions(rng, 200), directions(rng, 200)
    exact = k.eval(wi, wo)
    rounded = k.eval(wi.astype(np.float32), wo.astype(np.float32))
    assert exact.dtype == np.float64
    rel = np.abs(exact - rounded) / np.abs(exact)
    assert 0 < rel.max() < 1e-5
