"""Arrays in and out: (3, N) float32 C-contiguous is read in place; (N, 3),
float64 and strided views go through one conversion with the same results;
outputs take the layout of the first direction; shapes, dtypes and lengths
that do not fit raise TypeError / ValueError naming the argument."""

import numpy as np
import pytest

import facet
from facet import _facet
from conftest import material, directions


@pytest.fixture(scope="module")
def kernel():
    return facet.compile(material("plastic"))


def test_three_rows_float32_is_not_copied(rng):
    wi = np.ascontiguousarray(directions(rng, 100).T, dtype=np.float32)
    a0, a1, a2, copied = _facet._soa_addresses(wi)
    base = wi.ctypes.data
    assert (a0, a1, a2) == (base, base + 400, base + 800) and not copied


@pytest.mark.parametrize("make", [
    lambda d: d,                                          # (N, 3) float64
    lambda d: d.astype(np.float32),                       # (N, 3) float32
    lambda d: np.ascontiguousarray(d.T),                  # (3, N) float64
    lambda d: np.asfortranarray(d.T.astype(np.float32)),  # (3, N) float32, not C-contiguous
    lambda d: np.repeat(d.T.astype(np.float32), 2, axis=1)[:, ::2],  # a strided view
])
def test_other_layouts_are_converted_once_with_the_same_results(kernel, rng, make):
    d = directions(rng, 50)
    wo = directions(rng, 50)
    reference = kernel.eval(np.ascontiguousarray(d.T, dtype=np.float32), np.ascontiguousarray(wo.T, dtype=np.float32))
    a = make(d)
    assert _facet._soa_addresses(a)[3]  # copied
    got = kernel.eval(a, wo)
    rows = got if got.shape == (3, 50) else got.T
    assert np.array_equal(rows, reference)


def test_output_layouts(kernel, rng):
    wi, wo = directions(rng, 5), directions(rng, 5)
    assert kernel.eval(wi, wo).shape == (5, 3)
    assert kernel.eval(wi.T, wo.T).shape == (3, 5)
    assert kernel.eval(wi[0], wo[0]).shape == (3,)
    assert kernel.eval(wi[0], wo).shape == (5, 3)  # one direction broadcast to every lane
    assert kernel.pdf(wi, wo).shape == (5,)
    assert kernel.pdf(wi[0], wo[0]).shape == ()
    wi3, pdf, weight = kernel.sample(wo, np.full((5, 3), 0.5))
    assert (wi3.shape, pdf.shape, weight.shape) == ((5, 3), (5,), (5, 3))
    # (3, 3) is three directions as rows.
    three = kernel.eval(wi[:3], wo[:3])
    assert np.array_equal(three[1], kernel.eval(wi[1], wo[1]))
    assert kernel.eval(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 3)


def test_inputs_by_keyword(kernel, rng):
    wi, wo = directions(rng, 4), directions(rng, 4)
    default = kernel.eval(wi, wo)
    assert np.array_equal(kernel.eval(wi, wo, roughness=0.4, albedo=(0.6, 0.05, 0.04)), default)
    per_lane = kernel.eval(wi, wo, roughness=np.array([0.1, 0.4, 0.7, 1.0]))
    assert np.array_equal(per_lane[1], default[1]) and not np.array_equal(per_lane[0], default[0])
    rgb_lanes = kernel.eval(wi, wo, albedo=np.tile([0.6, 0.05, 0.04], (4, 1)))
    assert np.array_equal(rgb_lanes, default)
    # Beyond float but in double: clamped to the declared range first (1e39 -> 1).
    assert np.array_equal(kernel.eval(wi, wo, roughness=1e39), kernel.eval(wi, wo, roughness=1.0))
    names = [i.name for i in kernel.inputs]
    assert names == ["roughness", "albedo"]
    assert kernel.inputs[0].range == (0.0, 1.0) and kernel.inputs[1].type == "rgb"


def test_invalid_lanes_are_reported_and_the_others_kept(kernel, rng):
    wi, wo = directions(rng, 6), directions(rng, 6)
    good = kernel.eval(wi, wo)
    wi[2] = [np.inf, 0, 0]
    wo[4] = [0, 0, 2.0]  # not unit
    rgb, invalid = kernel.eval(wi, wo, status=True)
    assert invalid.tolist() == [False, False, True, False, True, False]
    assert np.all(rgb[invalid] == 0)
    assert np.array_equal(rgb[~invalid], good[~invalid])
    _, bad = kernel.pdf(wi, wo, status=True)
    assert bad == 2
    *_, bad = kernel.sample(wo, np.full((6, 3), 1.5), status=True)  # u outside [0, 1)
    assert bad == 6


@pytest.mark.parametrize("call, error, words", [
    (lambda k: k.eval([[0, 0, 1]] * 3, [[0, 0, 1]] * 4), ValueError, ["wi", "3 vectors", "wo has 4"]),
    (lambda k: k.eval(np.zeros((4, 4)), np.zeros((4, 3))), ValueError, ["wi", "(N, 3), (3, N) or (3,)", "(4, 4)"]),
    (lambda k: k.eval(np.zeros(2), np.zeros(3)), ValueError, ["wi", "(2,)"]),
    (lambda k: k.eval(["a", "b", "c"], [0, 0, 1]), TypeError, ["wi", "real numbers"]),
    (lambda k: k.eval([0, 0, 1], [0, 0, 1j]), TypeError, ["wo", "real numbers"]),
    (lambda k: k.eval([0, 0, 1], object()), TypeError, ["wo"]),
    (lambda k: k.eval([[0, 0, 1]] * 2, [[0, 0, 1]] * 2, roughness=[0.1, 0.2, 0.3]), ValueError,
     ["input 'roughness'", "2 values"]),
    (lambda k: k.eval([0, 0, 1], [0, 0, 1], roughness="rough"), TypeError, ["input 'roughness'"]),
    (lambda k: k.eval([0, 0, 1], [0, 0, 1], albedo=(1, 2)), ValueError, ["input 'albedo'"]),
    (lambda k: k.eval([0, 0, 1], [0, 0, 1], shininess=3), TypeError, ["no input 'shininess'", "roughness, albedo"]),
    (lambda k: k.sample([0, 0, 1], np.zeros((2, 2))), ValueError, ["u"]),
    (lambda k: k.pdf([0, 0, 1], None), TypeError, ["wo"]),
])
def test_bad_arguments_raise_naming_them(kernel, call, error, words):
    with pytest.raises(error) as info:
        call(kernel)
    for w in words:
        assert w in str(info.value)
