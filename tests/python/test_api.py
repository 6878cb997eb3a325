"""compile(), check(), the errors they raise, and what a kernel says about
itself."""

import os

import numpy as np
import pytest

import facet
from conftest import material, directions


def test_compile_a_file_and_a_text():
    k = facet.compile(material("plastic"))
    assert (k.material, k.backend, k.variant) == ("plastic", "simd", "exact")
    assert k.width in (4, 8, 16)
    text = open(material("plastic")).read()
    t = facet.compile(text=text, backend="scalar", math="fast")
    assert (t.backend, t.width, t.variant) == ("scalar", 1, "fast")
    assert t.options["canonical"].startswith("backend=scalar;math=fast")
    assert facet.compile(material("car_paint"), material="car_paint").material == "car_paint"


def test_set_binds_an_input():
    k = facet.compile(material("plastic"), set={"roughness": 0.2, "albedo": (0.1, 0.2, 0.3)})
    assert k.inputs == []
    free = facet.compile(material("plastic"))
    wi, wo = np.array([0.3, 0.1, 0.95]), np.array([-0.2, 0.0, 0.98])
    wi, wo = wi / np.linalg.norm(wi), wo / np.linalg.norm(wo)
    assert np.allclose(k.eval(wi, wo), free.eval(wi, wo, roughness=0.2, albedo=(0.1, 0.2, 0.3)), rtol=1e-6)


def test_a_material_error_carries_its_place():
    text = "material m {\n    ndf = ggx(0.3);\n    fresnel = bogus;\n}\n"
    with pytest.raises(facet.MaterialError) as info:
        facet.compile(text=text)
    e = info.value
    assert (e.file, e.line, e.column) == ("<text>", 3, 15)
    assert "unknown fresnel model 'bogus'" in e.message
    assert str(e).startswith("<text>:3:15: error: unknown fresnel model")
    assert len(e.diagnostics) == 1


def test_check_lists_every_error():
    text = "material m {\n    ndf = ggx(0.3)\n}\nmaterial n { ndf = nope; }\n"
    found = facet.check(text)
    assert [(d.line, d.column) for d in found][:1] == [(3, 1)]
    assert all(isinstance(d, facet.Diagnostic) for d in found)
    assert facet.check(path=material("plastic")) == []
    assert facet.check(material("plastic")) == []
    missing = facet.check(path="/nonexistent/x.mat")
    assert len(missing) == 1 and "cannot open" in missing[0].message


def test_bad_compile_calls():
    with pytest.raises(FileNotFoundError):
        facet.compile("/nonexistent/x.mat")
    with pytest.raises(TypeError, match="exactly one of path= and text="):
        facet.compile()
    with pytest.raises(ValueError, match="width '3' is not 4, 8 or 16"):
        facet.compile(material("plastic"), width=3)
    with pytest.raises(TypeError, match="width: expected an int"):
        facet.compile(material("plastic"), width="8")
    with pytest.raises(ValueError, match="backend 'gpu' is not scalar, simd or interp"):
        facet.compile(material("plastic"), backend="gpu")
    with pytest.raises(ValueError, match="';' separates options"):
        facet.compile(material("plastic"), backend="simd;math=fast")
    with pytest.raises(TypeError, match="unexpected option 'speed'"):
        facet.compile(material("plastic"), speed="fast")
    with pytest.raises(TypeError, match="float_first"):
        facet.compile(material("plastic"), float_first="yes")
    with pytest.raises(ValueError, match="set: roughness"):
        facet.compile(material("plastic"), set={"roughness": (1, 2)})
    with pytest.raises(facet.MaterialError, match="no material named 'nope'|nope"):
        facet.compile(material("plastic"), material="nope")
    with pytest.raises(facet.MaterialError, match="set.shininess|shininess"):
        facet.compile(material("plastic"), set={"shininess": 1.0})


def test_sampler_and_interpreter():
    k = facet.compile(material("plastic"))
    assert k.sampler == "jit"
    assert facet.compile(material("plastic"), backend="interp").sampler == "reference"


def test_sample_is_consistent_with_pdf_and_eval(rng):
    k = facet.compile(material("plastic"), backend="interp")
    wo = directions(rng, 1000)
    wi, pdf, weight = k.sample(wo, rng.random((1000, 3)))
    ok = (pdf > 0) & (wi[:, 2] > 0)
    assert ok.sum() > 900
    assert np.allclose(k.pdf(wi[ok], wo[ok]), pdf[ok], rtol=1e-9)
    f = k.eval(wi[ok], wo[ok])
    assert np.allclose(weight[ok], f * wi[ok, 2:3] / pdf[ok, None], rtol=1e-9)


def test_a_refracting_lobe_through_the_reference_and_simd():
    # SPEC 11: backend="interp" evaluates and samples a rough dielectric over
    # the whole sphere; transport="importance" drops the 1/eta^2 of radiance.
    text = ("material glass { ndf = ggx(0.3); masking = smith_height_correlated; "
            "fresnel = dielectric(1.5); scatter = both; }\n")
    radiance = facet.compile(text=text, backend="interp")
    importance = facet.compile(text=text, backend="interp", transport="importance")
    assert importance.options["canonical"].endswith("transport=importance")
    wi = np.array([-0.2, -0.1, -0.974679]) / np.linalg.norm([-0.2, -0.1, -0.974679])
    wo = np.array([0.4, 0.1, 0.910494]) / np.linalg.norm([0.4, 0.1, 0.910494])
    r, i = radiance.eval(wi, wo)[0], importance.eval(wi, wo)[0]
    assert r > 0 and i == pytest.approx(r * 1.5 ** 2, rel=1e-12)
    u = np.random.default_rng(3).random((4000, 3))
    s_wi, pdf, weight = radiance.sample(np.tile(wo, (4000, 1)), u)
    assert (s_wi[:, 2] < 0).mean() > 0.8  # glass at 24 degrees transmits most of the light
    # The SIMD kernel evaluates it in either transport, within exact mode's
    # bound, and its compensated form too (more than the single scattering).
    compensated = text.replace("scatter = both;", "scatter = both; energy = kulla_conty;")
    for transport, want in (("radiance", r), ("importance", i)):
        simd = facet.compile(text=text, backend="simd", transport=transport)
        assert simd.eval(wi, wo)[0] == pytest.approx(want, rel=1e-5)
        ref = facet.compile(text=compensated, backend="interp", transport=transport).eval(wi, wo)[0]
        assert ref > want
        simd = facet.compile(text=compensated, backend="simd", transport=transport)
        assert simd.eval(wi, wo)[0] == pytest.approx(ref, rel=1e-5)
    with pytest.raises(ValueError, match="transport 'photons' is not radiance or importance"):
        facet.compile(text=text, backend="interp", transport="photons")


def test_a_compensated_refracting_lobe_is_reciprocal_and_keeps_its_energy():
    # energy = kulla_conty from both sides: generalized reciprocity
    # f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2 in radiance transport, and in
    # importance transport the mean sample weight from inside (R + T, in
    # power) is 1 within 1% plus the estimate's noise, where the lobe without
    # compensation loses more than 20%.
    body = ("ndf = ggx(0.8); masking = smith_height_correlated; fresnel = dielectric(1.5); "
            "scatter = both; energy = {};")
    compensated = facet.compile(text="material g { " + body.format("kulla_conty") + " }\n", backend="interp")
    wi = np.array([-0.2, -0.1, -0.974679]) / np.linalg.norm([-0.2, -0.1, -0.974679])
    wo = np.array([0.4, 0.1, 0.910494]) / np.linalg.norm([0.4, 0.1, 0.910494])
    a, b = compensated.eval(wi, wo)[0], compensated.eval(wo, wi)[0]
    assert a > 0 and a / 1.0 == pytest.approx(b / 1.5 ** 2, rel=1e-9)
    u = np.random.default_rng(5).random((20000, 3))
    inside = np.tile(-wo, (20000, 1))
    for energy, low, high in (("kulla_conty", 0.99, 1.01), ("none", 0.0, 0.8)):
        k = facet.compile(text="material g { " + body.format(energy) + " }\n", backend="interp",
                          transport="importance")
        _, _, weight = k.sample(inside, u)
        mean, err = weight[:, 0].mean(), weight[:, 0].std() / np.sqrt(len(u))
        assert low - 4 * err <= mean <= high + 4 * err, (energy, mean, err)
