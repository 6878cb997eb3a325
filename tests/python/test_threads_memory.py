"""Many Python threads on one kernel (batch calls release the GIL) give the
serial bits; compiling and releasing kernels 10,000 times keeps the
process's memory flat."""

import gc
import threading

import numpy as np

import facet
from conftest import material, directions


def test_eight_threads_on_one_kernel_give_the_serial_bits(rng):
    k = facet.compile(material("car_paint"))
    batches = [(directions(rng, 4096), directions(rng, 4096), rng.random((4096, 3))) for _ in range(16)]
    serial = [(k.eval(wi, wo), k.sample(wo, u), k.pdf(wi, wo)) for wi, wo, u in batches]
    results = [None] * (8 * len(batches))
    errors = []

    def work(t):
        try:
            for j, (wi, wo, u) in enumerate(batches):
                results[t * len(batches) + j] = (k.eval(wi, wo), k.sample(wo, u), k.pdf(wi, wo))
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(t,)) for t in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for i, (rgb, (wi, pdf, weight), p) in enumerate(results):
        s_rgb, (s_wi, s_pdf, s_weight), s_p = serial[i % len(batches)]
        assert np.array_equal(rgb, s_rgb) and np.array_equal(p, s_p)
        assert np.array_equal(wi, s_wi) and np.array_equal(pdf, s_pdf) and np.array_equal(weight, s_weight)


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_compile_and_release_cycles_keep_memory_flat(rng):
    wi, wo = directions(rng, 64), directions(rng, 64)

    def cycles(n):
        for _ in range(n):
            k = facet.compile(material("plastic"))  # a memory-cache hit after the first
            k.eval(wi, wo)
            del k

    cycles(1000)  # warm: the cache entry, the allocator's pools
    gc.collect()
    before = resident_bytes()
    cycles(10_000)
    gc.collect()
    grown = resident_bytes() - before
    # A leak of one kernel's code or tables per cycle (>= tens of KB) would
    # grow by hundreds of MB; allow the allocator some slack.
    assert grown < 16 << 20, f"resident memory grew by {grown / 2**20:.1f} MB over 10,000 cycles"
