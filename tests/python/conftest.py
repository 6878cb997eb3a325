"""Shared pieces of the Python package's tests: the shipped materials, random
directions, and the C API through ctypes (libfacet.so of this build), which
the package's results are compared with bit for bit."""

import ctypes
import os

import numpy as np
import pytest

SOURCE = os.environ.get("FACET_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
MATERIALS = os.path.join(SOURCE, "materials")


def material(name):
    return os.path.join(MATERIALS, name + ".mat")


def directions(rng, n, upper=True):
    """n unit directions as an (n, 3) float64 array (upper hemisphere: z > 0)."""
    v = rng.normal(size=(n, 3))
    if upper:
        v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v / np.linalg.norm(v, axis=1, keepdims=True)


class CApi:
    """The few C API calls the tests compare with (runtime/include/facet/facet.h)."""

    def __init__(self, path):
        lib = ctypes.CDLL(path)
        P = ctypes.c_void_p
        lib.facet_compile_file.restype = P
        lib.facet_compile_file.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p,
                                           ctypes.c_size_t]
        rows = ctypes.POINTER(ctypes.c_void_p)
        for fn in ("facet_eval_batch_status", "facet_sample_batch", "facet_pdf_batch"):
            getattr(lib, fn).restype = ctypes.c_int64
        lib.facet_input_count.argtypes = [P]
        lib.facet_input_name.argtypes = [P, ctypes.c_int]
        lib.facet_input_name.restype = ctypes.c_char_p
        lib.facet_release.argtypes = [P]
        self.lib = lib

    def compile(self, path, options):
        err = ctypes.create_string_buffer(4096)
        k = self.lib.facet_compile_file(path.encode(), None, options.encode(), err, len(err))
        assert k, err.value.decode()
        return k

    @staticmethod
    def _rows(a):
        """A (3, n) float32 C-contiguous array as the C API's float* [3]."""
        assert a.dtype == np.float32 and a.flags.c_contiguous and a.shape[0] == 3
        arr = (ctypes.c_void_p * 3)(*(a.ctypes.data + k * a.shape[1] * 4 for k in range(3)))
        return arr

    @staticmethod
    def _slots(columns):
        if not columns:
            return None
        return (ctypes.c_void_p * len(columns))(*(c.ctypes.data for c in columns))

    def eval(self, k, wi, wo, slots):
        n = wi.shape[1]
        rgb = np.zeros((3, n), np.float32)
        status = np.zeros(n, np.uint8)
        bad = self.lib.facet_eval_batch_status(ctypes.c_void_p(k), ctypes.c_int64(n), self._rows(wi), self._rows(wo),
                                               self._slots(slots), self._rows(rgb), status.ctypes.data_as(ctypes.c_void_p))
        return rgb, status, bad

    def sample(self, k, wo, u, slots):
        n = wo.shape[1]
        wi = np.zeros((3, n), np.float32)
        weight = np.zeros((3, n), np.float32)
        pdf = np.zeros(n, np.float32)
        bad = self.lib.facet_sample_batch(ctypes.c_void_p(k), ctypes.c_int64(n), self._rows(wo), self._rows(u),
                                          self._slots(slots), self._rows(wi), pdf.ctypes.data_as(ctypes.c_void_p),
                                          self._rows(weight))
        return wi, pdf, weight, bad

    def pdf(self, k, wi, wo, slots):
        n = wi.shape[1]
        pdf = np.zeros(n, np.float32)
        bad = self.lib.facet_pdf_batch(ctypes.c_void_p(k), ctypes.c_int64(n), self._rows(wi), self._rows(wo),
                                       self._slots(slots), pdf.ctypes.data_as(ctypes.c_void_p))
        return pdf, bad

    def release(self, k):
        self.lib.facet_release(ctypes.c_void_p(k))


@pytest.fixture(scope="session")
def capi():
    path = os.environ.get("FACET_LIBRARY")
    if not path:
        pytest.skip("FACET_LIBRARY (libfacet.so) not set: run through ctest")
    return CApi(path)


@pytest.fixture
def rng():
    return np.random.default_rng(20261129)
