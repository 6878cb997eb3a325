#!/usr/bin/env python3
"""reference_walk.py -- an independent Python random walk on the Smith microsurface.

The second implementation that Facet's C++ random walk (compiler/reference/
MicrosurfaceWalk.h, SPEC 13) is checked against: the multiple-scattering
microfacet BSDF of Heitz, Hanika, d'Eon & Dachsbacher 2016, written from the
paper, with nothing shared with the C++ code but the formulas of D and Lambda
in SPEC 3. Where the C++ makes a choice, this script makes another one, so that
agreement means more than a transcription:

- heights: Gaussian (C1 = the normal CDF), where the C++ uses the uniform
  distribution and tracks the CDF value alone; the paper shows the BSDF does
  not depend on the choice, so the two must agree;
- the next height in the paper's signed form, h' = C1^-1(C1(h) / (1 - U)^(1/Lambda(w)))
  with Lambda(w) = -1 - Lambda(-w) for a ray going down;
- visible normals: GGX by Heitz 2018's projected hemisphere (not spherical
  caps), Beckmann by bisection of the slope CDF (not Newton) with y from the
  normal quantile; below the horizon (a ray going up meets facets facing
  down) both by rejection from the mirrored direction's visible normals.

With F = 1 every walk leaves with weight 1, so its scattering order is what
the walk computes: the script prints, per NDF, alpha and theta_o, the fraction
of walks that leave after 1, 2 and 3 or more reflections with its standard
error. Order 1 is the single-scattering albedo with height-correlated Smith
masking.

Usage:
  reference_walk.py [--paths N] [--seed S]     print the table (the file
        tests/stochastic/walk_orders.txt is this command's output with its
        defaults; a few minutes, pure Python)
"""

import argparse
import math
import random
import statistics

from reference_values import dot, normalize

PI = math.pi
NORMAL = statistics.NormalDist()

CELLS = [(ndf, alpha, theta) for ndf in ("ggx", "beckmann") for alpha in (0.3, 0.6, 1.0)
         for theta in (0.0, 60.0, 85.0)]


# ---- the NDFs: Lambda for a direction above the horizon -------------------

def lambda_up(ndf, alpha, w):
    """Smith Lambda(w), w.z > 0 (SPEC 3), isotropic alpha."""
    s2 = w[0] * w[0] + w[1] * w[1]
    if s2 == 0:
        return 0.0
    if w[2] <= 0:
        return math.inf
    a = w[2] / (alpha * math.sqrt(s2))  # 1 / (alpha tan theta)
    if ndf == "ggx":
        return (-1 + math.sqrt(1 + 1 / (a * a))) / 2
    return (math.exp(-a * a) / (a * math.sqrt(PI)) - math.erfc(a)) / 2


def lambda_signed(ndf, alpha, w):
    """The paper's Lambda for any direction: -1 - Lambda(-w) below the horizon."""
    if w[2] > 0:
        return lambda_up(ndf, alpha, w)
    return -1 - lambda_up(ndf, alpha, (-w[0], -w[1], -w[2]))


# ---- visible normals ------------------------------------------------------

def ggx_visible_up(alpha, v, u1, u2):
    """Heitz 2018: the projected hemisphere of the stretched view direction."""
    vh = normalize((alpha * v[0], alpha * v[1], v[2]))
    lensq = vh[0] * vh[0] + vh[1] * vh[1]
    t1 = (-vh[1] / math.sqrt(lensq), vh[0] / math.sqrt(lensq), 0.0) if lensq > 0 else (1.0, 0.0, 0.0)
    t2 = (vh[1] * t1[2] - vh[2] * t1[1], vh[2] * t1[0] - vh[0] * t1[2], vh[0] * t1[1] - vh[1] * t1[0])
    r = math.sqrt(u1)
    phi = 2 * PI * u2
    p1, p2 = r * math.cos(phi), r * math.sin(phi)
    s = 0.5 * (1 + vh[2])
    p2 = (1 - s) * math.sqrt(max(0.0, 1 - p1 * p1)) + s * p2
    p3 = math.sqrt(max(0.0, 1 - p1 * p1 - p2 * p2))
    nh = tuple(p1 * t1[i] + p2 * t2[i] + p3 * vh[i] for i in range(3))
    return normalize((alpha * nh[0], alpha * nh[1], max(0.0, nh[2])))


def beckmann_visible_up(alpha, v, u1, u2):
    """Slopes in the frame where the stretched v is (sin t, 0, cos t): x from
    the CDF cos t erfc(-x)/2 + sin t exp(-x^2)/(2 sqrt(pi)) on x < cot t by
    bisection, y from the normal quantile (variance 1/2)."""
    sx, sy, sz = alpha * v[0], alpha * v[1], v[2]
    sxy = math.hypot(sx, sy)
    length = math.sqrt(sxy * sxy + sz * sz)
    sint, cost = sxy / length, sz / length
    cphi, sphi = (sx / sxy, sy / sxy) if sxy > 0 else (1.0, 0.0)

    def cdf(x):
        return cost * math.erfc(-x) / 2 + sint * math.exp(-x * x) / (2 * math.sqrt(PI))

    hi = cost / sint if sint > 0 and cost / sint < 10 else 10.0
    lo = -10.0
    target = u1 * cdf(hi)
    for _ in range(80):
        mid = (lo + hi) / 2
        if cdf(mid) < target:
            lo = mid
        else:
            hi = mid
    x = (lo + hi) / 2
    y = NORMAL.inv_cdf(min(max(u2, 1e-300), 1 - 1e-16)) / math.sqrt(2)
    mx, my = cphi * x - sphi * y, sphi * x + cphi * y
    return normalize((-alpha * mx, -alpha * my, 1.0))


def visible_normal(ndf, alpha, v, rng):
    up_sampler = ggx_visible_up if ndf == "ggx" else beckmann_visible_up
    if v[2] > 0:
        return up_sampler(alpha, v, rng.random(), rng.random())
    mirrored = (v[0], v[1], -v[2] if v[2] < 0 else 1e-300)
    while True:
        m = up_sampler(alpha, mirrored, rng.random(), rng.random())
        along = dot(v, m)
        if along > 0 and rng.random() * dot(mirrored, m) < along:
            return m


# ---- the walk -------------------------------------------------------------

def walk_order(ndf, alpha, wo, rng):
    """Reflections before the walk from wo leaves (F = 1)."""
    w = (-wo[0], -wo[1], -wo[2])
    h = math.inf
    order = 0
    while True:
        u = rng.random()
        lam = lambda_signed(ndf, alpha, w)
        c1 = 1.0 if h == math.inf else NORMAL.cdf(h)
        if w[2] > 0:
            if lam == 0 or u >= 1 - c1 ** lam:
                return order
        c1_next = c1 / (1 - u) ** (1 / lam)  # going down lam <= -1: a meeting always
        c1_next = min(max(c1_next, 1e-300), 1 - 1e-16)
        h = NORMAL.inv_cdf(c1_next)
        order += 1
        m = visible_normal(ndf, alpha, (-w[0], -w[1], -w[2]), rng)
        d = 2 * dot(w, m)
        w = normalize((w[0] - d * m[0], w[1] - d * m[1], w[2] - d * m[2]))


def cell(ndf, alpha, theta, paths, seed):
    rng = random.Random(seed)
    t = math.radians(theta)
    wo = (math.sin(t), 0.0, math.cos(t))
    counts = [0, 0, 0]
    for _ in range(paths):
        k = walk_order(ndf, alpha, wo, rng)
        counts[min(k, 3) - 1] += 1
    out = []
    for c in counts:
        p = c / paths
        out += [p, math.sqrt(p * (1 - p) / paths)]
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--paths", type=int, default=40000)
    parser.add_argument("--seed", type=int, default=2016)
    args = parser.parse_args()
    print("# scripts/reference_walk.py --paths %d --seed %d: F = 1, the fraction of walks leaving after" %
          (args.paths, args.seed))
    print("# 1, 2 and >= 3 reflections, each with its standard error")
    print("# ndf alpha theta_o paths  e1 se1  e2 se2  e3+ se3+")
    for i, (ndf, alpha, theta) in enumerate(CELLS):
        values = cell(ndf, alpha, theta, args.paths, args.seed + i)
        print("%s %g %g %d  %s" % (ndf, alpha, theta, args.paths, "  ".join("%.6f %.6f" % (values[j], values[j + 1])
                                                                         for j in (0, 2, 4))), flush=True)


if __name__ == "__main__":
    main()
