"""The cost of calling a kernel from Python, next to the library's own call.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/call_overhead.py [material.mat]

For N = 1 and N = 65536 lanes of (3, N) float32 directions (the layout read
in place), prints the time per kernel.eval call from Python, the time per
Kernel::evalBatch call timed in C++ on the same arrays (facet_eval_batch
forwards to it), and the difference: what the binding adds (argument
parsing, the output array, releasing the GIL). Each figure is the median of
nine rounds, the Python and the library rounds alternating.
"""

import os
import sys
import time

import numpy as np

import facet
from facet import _facet

here = os.path.dirname(os.path.abspath(__file__))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "materials", "plastic.mat")
kernel = facet.compile(path, codegen="optimized")
rng = np.random.default_rng(1)


def directions(n):
    v = rng.normal(size=(3, n))
    v[2] = np.abs(v[2]) + 1e-3
    return np.ascontiguousarray(v / np.linalg.norm(v, axis=0), dtype=np.float32)


print(f"{os.path.basename(path)}: {kernel.backend} width {kernel.width}, {kernel.variant}")
print(f"{'N':>6} {'python eval':>14} {'library call':>14} {'overhead':>16}")
for n, calls in ((1, 40_000), (65536, 80)):
    wi, wo = directions(n), directions(n)
    py_rounds, lib_rounds = [], []
    for _ in range(9):  # alternating, so that a slow spell of the machine hits both
        start = time.perf_counter()
        for _ in range(calls):
            kernel.eval(wi, wo)
        py_rounds.append((time.perf_counter() - start) / calls)
        lib_rounds.append(_facet._time_eval_batch(kernel, wi, wo, calls))
    py, lib = sorted(py_rounds)[4], sorted(lib_rounds)[4]
    unit = 1e9 if n == 1 else 1e6
    label = "ns" if n == 1 else "us"
    print(f"{n:>6} {py * unit:>11.1f} {label} {lib * unit:>11.1f} {label} "
          f"{(py - lib) * 1e9:>8.0f} ns {100 * (py - lib) / lib:>5.1f}%")
