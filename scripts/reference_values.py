#!/usr/bin/env python3
"""reference_values.py -- an independent Python reference for the Facet test corpus.

The numbers in tests/corpus/**/*.mat `// expect:` lines come from this script.
It re-implements, from SPEC sections 1-3 only (never from the C++ sources), both
the small material language (enough of it for valid files) and the BRDF formulas,
using nothing but the Python standard library (math, cmath). Where the C++
interpreter and this script agree on a value, two independent readings of the
spec agree; where they disagree, one of them has a bug.

Independence is deliberate in the formulas too: the dielectric Fresnel uses
Walter et al.'s g-form, the conductor Fresnel the real-arithmetic form (not a
complex sqrt), the Gaussian normalization its own adaptive Gauss-Legendre
quadrature with nodes computed here by Newton iteration, and the Smith Lambda
of the NDFs without a closed form a 2-D quadrature of a different integral
than the one Facet tabulates.

Lobes that scatter below the surface (SPEC 11) are evaluated by
reference_transmission.py. Materials of several lobes (SPEC 10: lobe blocks, bsdf = EXPR, layer) and
energy = kulla_conty are evaluated by reference_lobes.py, independent in the
same way (its own albedo quadrature and its own solve of the layer's balance).

Usage:
  reference_values.py --eval FILE [--material NAME] [tol=T] wi=(x,y,z) wo=(x,y,z) [NAME=V | NAME=(r,g,b)]...
        print the `// expect:` line for one evaluation
  reference_values.py --update FILE...
        rewrite the numbers after `->` of every expect line (`-> ?` is a placeholder);
        files marked `// values: by hand` are left alone
  reference_values.py --check [PATH...]      (default: tests/corpus)
        recompute every expect line; report each mismatch; exit 1 on any
  reference_values.py --selftest
        quadrature and normalization checks of this script's own formulas

Expect-line syntax (shared with tests/corpus/CorpusRunner.cpp):
  // expect: wi=(x,y,z) wo=(x,y,z) [NAME=V | NAME=(r,g,b)]... [tol=T] -> r g b     (or a single v when r=g=b)
  // material: NAME      selects the material for the following expect lines
"""

import cmath
import math
import os
import re
import sys

PI = math.pi
MIN_ALPHA = 1e-4          # SPEC 3: alpha is clamped to >= 1e-4
DEFAULT_TOL = 1e-9        # relative tolerance of an expect line without tol=

# ---------------------------------------------------------------------------
# Quadrature (for the Gaussian NDF normalization and the self-test)
# ---------------------------------------------------------------------------


def _legendre_nodes(n):
    """Gauss-Legendre nodes and weights on [-1, 1], by Newton iteration on P_n."""
    nodes, weights = [], []
    for i in range(1, n + 1):
        x = math.cos(PI * (i - 0.25) / (n + 0.5))  # Tricomi's initial guess
        for _ in range(100):
            p_prev, p = 1.0, x
            for k in range(2, n + 1):
                p_prev, p = p, ((2 * k - 1) * x * p - (k - 1) * p_prev) / k
            dp = n * (x * p - p_prev) / (x * x - 1)
            step = p / dp
            x -= step
            if abs(step) < 1e-17:
                break
        p_prev, p = 1.0, x
        for k in range(2, n + 1):
            p_prev, p = p, ((2 * k - 1) * x * p - (k - 1) * p_prev) / k
        dp = n * (x * p - p_prev) / (x * x - 1)
        nodes.append(x)
        weights.append(2 / ((1 - x * x) * dp * dp))
    return nodes, weights


_GL = _legendre_nodes(20)


def _gl(f, a, b):
    half, mid = (b - a) / 2, (a + b) / 2
    return half * math.fsum(w * f(mid + half * x) for x, w in zip(*_GL))


def integrate(f, a, b, rel=1e-13, depth=0, floor=0.0):
    """Adaptive 20-point Gauss-Legendre: split until both halves agree with the whole.

    The 20-point rule's error falls like h^40, so once the whole and the two
    halves agree to `rel` the halves are accurate to far better than that;
    asking for much less than 1e-13 would only chase rounding noise. `floor`:
    an absolute difference that counts as agreement too (a panel whose share
    of a larger integral is below what matters; without it a panel where the
    integrand is rounding noise would split to the depth limit).
    """
    whole = _gl(f, a, b)
    m = (a + b) / 2
    left, right = _gl(f, a, m), _gl(f, m, b)
    diff = abs(left + right - whole)
    if diff <= rel * abs(left + right) or diff <= floor or depth > 30 or left + right == 0:
        return left + right
    return integrate(f, a, m, rel, depth + 1, floor) + integrate(f, m, b, rel, depth + 1, floor)


_gaussian_norm_cache = {}


def gaussian_norm(alpha):
    """N(alpha) = 2 pi Int_0^{pi/2} exp(-t^2/alpha^2) cos t sin t dt.

    Substituting t = alpha*u puts the peak near u ~ 0.7 whatever alpha is, so the
    quadrature sees it; beyond u = 40 the integrand is below exp(-1600) = 0.
    """
    if alpha not in _gaussian_norm_cache:
        upper = min(PI / (2 * alpha), 40.0)
        f = lambda u: math.exp(-u * u) * math.cos(alpha * u) * math.sin(alpha * u)
        # Split at fixed points so each panel is smooth and well resolved.
        cuts = [0.0] + [c for c in (1.0, 2.0, 4.0, 8.0, 16.0) if c < upper] + [upper]
        total = math.fsum(integrate(f, cuts[i], cuts[i + 1]) for i in range(len(cuts) - 1))
        _gaussian_norm_cache[alpha] = 2 * PI * alpha * total
    return _gaussian_norm_cache[alpha]


_abc_norm_cache = {}


def abc_norm(b, c):
    """2 pi Int_0^1 (1 - x) (1 + b x)^-c dx (x = 1 - cos theta): 1/A of the ABC NDF.

    In s = b x the integrand (1 - s/b) (1 + s)^-c is smooth on panels that grow
    fourfold from s = 1 up to s = b, so the peak of a large b is resolved.
    """
    if (b, c) not in _abc_norm_cache:
        f = lambda s: (1 - s / b) * (1 + s) ** -c
        cuts = [0.0]
        while cuts[-1] * 4 + 1 < b:
            cuts.append(cuts[-1] * 4 + 1)
        cuts.append(b)
        total = math.fsum(integrate(f, cuts[i], cuts[i + 1]) for i in range(len(cuts) - 1))
        _abc_norm_cache[(b, c)] = 2 * PI * total / b
    return _abc_norm_cache[(b, c)]


_sgd_norm_cache = {}


def sgd_norm(alpha, q):
    """pi alpha Int_alpha^inf w^-q e^-w dw: the normalization of the SGD NDF.

    Panels doubling from w = alpha resolve the w^-q peak of a small alpha; beyond
    alpha + 45 the integrand is below e^-45 of its scale.
    """
    if (alpha, q) not in _sgd_norm_cache:
        f = lambda w: w ** -q * math.exp(-w)
        cuts = [alpha]
        while cuts[-1] < alpha + 45:
            cuts.append(cuts[-1] * 2)
        total = math.fsum(integrate(f, cuts[i], cuts[i + 1]) for i in range(len(cuts) - 1))
        _sgd_norm_cache[(alpha, q)] = PI * alpha * total
    return _sgd_norm_cache[(alpha, q)]


# ---------------------------------------------------------------------------
# Vectors
# ---------------------------------------------------------------------------


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(v):
    n = math.sqrt(dot(v, v))
    return (v[0] / n, v[1] / n, v[2] / n)


# ---------------------------------------------------------------------------
# SPEC 3: the model catalog. `p` is a dict of resolved (clamped) parameters.
# ---------------------------------------------------------------------------


def ndf_D(ndf, p, m):
    """D(m) of the NDF; m a unit microfacet normal. Zero below the horizon."""
    mx, my, mz = m
    if mz <= 0:
        return 0.0
    s2 = mx * mx + my * my  # sin^2 theta from the components (SPEC 3)
    if ndf == "ggx":
        ax, ay = p["alpha_x"], p["alpha_y"]
        t = mx * mx / (ax * ax) + my * my / (ay * ay) + mz * mz
        return 1.0 / (PI * ax * ay * t * t)
    if ndf == "beckmann":
        ax, ay = p["alpha_x"], p["alpha_y"]
        e = (mx * mx / (ax * ax) + my * my / (ay * ay)) / (mz * mz)
        return math.exp(-e) / (PI * ax * ay * mz ** 4)
    if ndf == "blinn_phong":
        e = p["exponent"]
        return (e + 2) / (2 * PI) * mz ** e
    if ndf == "gtr":
        a, g = p["alpha"], p["gamma"]
        a2 = a * a
        if a == 1.0:
            c = 1 / PI
        elif g == 1.0:
            c = (a2 - 1) / (PI * math.log(a2))
        else:
            c = (g - 1) * (a2 - 1) / (PI * (1 - a2 ** (1 - g)))
        # 1 + (a^2 - 1) mz^2 = a^2 mz^2 + sin^2: no cancellation near mz = 1.
        return c / (a2 * mz * mz + s2) ** g
    if ndf == "student_t":
        # Ribardiere et al. 2017: (1 + e/(g - 1))^-g / (pi ax ay mz^4),
        # e = (mx^2/ax^2 + my^2/ay^2)/mz^2; the power taken as exp(-g log1p(.)).
        ax, ay, g = p["alpha_x"], p["alpha_y"], p["gamma"]
        e = (mx * mx / (ax * ax) + my * my / (ay * ay)) / (mz * mz)
        return math.exp(-g * math.log1p(e / (g - 1))) / (PI * ax * ay * mz ** 4)
    if ndf == "epd":
        # Holzschuch & Pacanowski 2017 eq. 34-38: p exp(-e^p) / (pi Gamma(1/p) ax ay mz^4),
        # e = (mx^2/ax^2 + my^2/ay^2)/mz^2.
        ax, ay, q = p["alpha_x"], p["alpha_y"], p["p"]
        e = (mx * mx / (ax * ax) + my * my / (ay * ay)) / (mz * mz)
        return q * math.exp(-e ** q) / (PI * math.gamma(1 / q) * ax * ay * mz ** 4)
    if ndf == "abc":
        # Church et al. 1989 as used by Low et al. 2012: A / (1 + b (1 - mz))^c,
        # 1 - mz = sin^2 / (1 + mz); A normalizes the projected area (abc_norm).
        b, c = p["b"], p["c"]
        return (1 + b * s2 / (1 + mz)) ** -c / abc_norm(b, c)
    if ndf == "sgd":
        # Bagher et al. 2012: exp(-w) w^-p / (N cos^4), w = alpha + tan^2/alpha
        # (sgd_norm).
        a, q = p["alpha"], p["p"]
        w = a + s2 / (mz * mz) / a
        return math.exp(-w) * w ** -q / (sgd_norm(a, q) * mz ** 4)
    if ndf == "gaussian":
        a = p["alpha"]
        theta = math.atan2(math.sqrt(s2), mz)  # = acos(mz), accurate near 0
        return math.exp(-theta * theta / (a * a)) / gaussian_norm(a)
    raise ValueError("no D for ndf " + ndf)


def beckmann_lambda_of_a(a):
    # Lambda = (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)); erf(a) - 1 = -erfc(a)
    return -math.erfc(a) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(PI))


_lambda_cache = {}


def lambda_by_quadrature(ndf, p, v):
    """Smith Lambda(v) of any NDF whose D(m) = D(-m_t, m_z), by 2-D quadrature.

    Int (v.m) D(m) dm = n.v for such a D, so the projected area of the visible
    microsurface, Int (v.m)+ D dm = (n.v)(1 + Lambda), gives
      (n.v) Lambda(v) = Int_{v.m < 0} -(v.m) D(m) dm,
    the back-facing facets' projected area: a positive integrand, no
    cancellation against n.v where Lambda is tiny. (Facet's tables integrate
    the other form with the azimuth in closed form; this one integrates the
    azimuth numerically.) With u = m_z (dm = du dphi) and psi the azimuth of m
    measured from the one opposite v, the region is u < sin(theta_v),
    |psi| < acos(cot(theta_v) u / sqrt(1 - u^2)), where
    -(v.m) = sin(theta_v) sqrt(1 - u^2) cos(psi) - v_z u. The substitution
    u = sin(theta_v) t^4 grades the panels toward the horizon, where a heavy
    tail's D may grow like a negative power of u.
    """
    key = (ndf, tuple(sorted(p.items())), v)
    if key in _lambda_cache:
        return _lambda_cache[key]
    vx, vy, vz = v
    sv = math.hypot(vx, vy)
    if sv == 0:
        return 0.0
    phi_v = math.atan2(vy, vx)

    floor = 0.0  # set from a first, fixed-rule estimate of the whole integral

    def over_t(t):
        u = sv * t ** 4
        s = math.sqrt(1 - u * u)
        psi0 = math.acos(min(1.0, vz * u / (sv * s)))
        if psi0 == 0:
            return 0.0

        def over_psi(psi):
            phi = phi_v + PI + psi
            m = (s * math.cos(phi), s * math.sin(phi), u)
            return (sv * s * math.cos(psi) - vz * u) * ndf_D(ndf, p, m)

        return integrate(over_psi, -psi0, psi0, 1e-12, floor=floor) * 4 * sv * t ** 3

    cuts = [0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 1.0]
    estimate = math.fsum(_gl(over_t, cuts[i], cuts[i + 1]) for i in range(len(cuts) - 1))
    floor = 1e-15 * abs(estimate)
    lam = math.fsum(integrate(over_t, cuts[i], cuts[i + 1], 1e-12, floor=floor) for i in range(len(cuts) - 1)) / vz
    _lambda_cache[key] = lam
    return lam


def smith_lambda(ndf, p, v):
    vx, vy, vz = v
    if ndf not in ("ggx", "beckmann", "blinn_phong"):
        return lambda_by_quadrature(ndf, p, v)
    if ndf == "blinn_phong":
        ax = ay = math.sqrt(2 / (p["exponent"] + 2))
    else:
        ax, ay = p["alpha_x"], p["alpha_y"]
    proj = vx * vx * ax * ax + vy * vy * ay * ay
    if proj == 0:
        return 0.0  # v along n: tan theta = 0, nothing masked
    if ndf == "ggx":
        x = proj / (vz * vz)
        return x / (2 * (1 + math.sqrt(1 + x)))
    if ndf in ("beckmann", "blinn_phong"):
        return beckmann_lambda_of_a(vz / math.sqrt(proj))
    raise ValueError("no Smith Lambda for ndf " + ndf)


def azimuth_weight(wi, wo):
    phi = math.atan2(abs(wi[0] * wo[1] - wi[1] * wo[0]), wi[0] * wo[0] + wi[1] * wo[1])
    return 4.41 * phi / (4.41 * phi + 1)


def masking_G(masking, ndf, p, wi, wo, h):
    ni, no, nh = wi[2], wo[2], h[2]
    ih, oh = dot(wi, h), dot(wo, h)
    if masking == "none":
        return 1.0
    if masking == "implicit":
        return ni * no
    if masking == "cook_torrance":
        return min(1.0, 2 * nh * no / oh, 2 * nh * ni / oh)
    if masking == "kelemen":
        return ni * no / (oh * oh)
    if masking == "neumann":
        return ni * no / max(ni, no)
    if masking == "schlick_smith":
        k = p["k"]
        g1 = lambda c: c / (c * (1 - k) + k)
        return g1(ni) * g1(no)
    chi = 1.0 if (ih > 0 and oh > 0) else 0.0
    if chi == 0.0:
        return 0.0
    li, lo = smith_lambda(ndf, p, wi), smith_lambda(ndf, p, wo)
    if masking == "smith_separable":
        return 1 / ((1 + li) * (1 + lo))
    if masking == "smith_height_correlated":
        return 1 / (1 + li + lo)
    if masking == "smith_direction_correlated":
        g1i, g1o = 1 / (1 + li), 1 / (1 + lo)
        w = azimuth_weight(wi, wo)
        return w * g1i * g1o + (1 - w) * min(g1i, g1o)
    if masking == "smith_height_direction_correlated":
        return 1 / (1 + max(li, lo) + azimuth_weight(wi, wo) * min(li, lo))
    raise ValueError("unknown masking " + masking)


def fresnel_dielectric(c, eta):
    """Exact unpolarized Fresnel, Walter et al. 2007 form; TIR gives 1."""
    g2 = eta * eta - 1 + c * c
    if g2 <= 0:
        return 1.0
    g = math.sqrt(g2)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1) / (c * (g - c) + 1)
    return 0.5 * a * a * (1 + b * b)


def fresnel_conductor(c, eta, k):
    """Exact unpolarized Fresnel for index eta + ik, in real arithmetic.

    With a^2 + b^2 = |N^2 - sin^2| and a = Re sqrt(N^2 - sin^2):
      Rs = (a^2+b^2 - 2ac + c^2) / (a^2+b^2 + 2ac + c^2)
      Rp = Rs (c^2(a^2+b^2) - 2ac s^2 + s^4) / (c^2(a^2+b^2) + 2ac s^2 + s^4)
    """
    c2 = c * c
    s2 = 1 - c2
    t0 = eta * eta - k * k - 1 + c2  # = eta^2 - k^2 - s2, without the cancellation in s2 at small c
    a2b2 = math.sqrt(t0 * t0 + 4 * eta * eta * k * k)
    a = math.sqrt(max(0.0, 0.5 * (a2b2 + t0)))
    t1, t2 = a2b2 + c2, 2 * a * c
    rs = (t1 - t2) / (t1 + t2)
    t3, t4 = c2 * a2b2 + s2 * s2, t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)


def fresnel_F(fresnel, p, c, ch):
    if fresnel == "none":
        return 1.0
    if fresnel == "schlick":
        if "f0" in p:
            f0 = p["f0"][ch]
        else:
            eta = p["eta"][ch]
            f0 = ((eta - 1) / (eta + 1)) ** 2
        return f0 + (1 - f0) * (1 - c) ** 5
    if fresnel == "dielectric":
        return fresnel_dielectric(c, p["eta"][ch])
    if fresnel == "conductor":
        return fresnel_conductor(c, p["eta"][ch], p["k"][ch])
    raise ValueError("unknown fresnel " + fresnel)


def brdf(models, params, wi, wo):
    """SPEC 2: f = F(wi.h) G D / (4 n.wi n.wo) + albedo/pi; 0 below the horizon.

    Directions must be unit within 1e-3 and are renormalized; anything else is
    an invalid lane, which the corpus does not test (so it is an error here).
    """
    for name, w in (("wi", wi), ("wo", wo)):
        if not abs(math.sqrt(dot(w, w)) - 1) <= 1e-3:
            raise ValueError("%s = %s is not a unit vector within 1e-3" % (name, w))
    wi, wo = normalize(wi), normalize(wo)
    if wi[2] <= 0 or wo[2] <= 0:
        return (0.0, 0.0, 0.0)
    s = (wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2])
    if dot(s, s) == 0:
        return (0.0, 0.0, 0.0)
    h = normalize(s)
    c = min(1.0, dot(wi, h))
    ndf, masking, fresnel, diffuse = models["ndf"], models["masking"], models["fresnel"], models["diffuse"]
    pn, pm, pf = params["ndf"], params["masking"], params["fresnel"]
    if ndf == "ward":
        ax, ay = pn["alpha_x"], pn["alpha_y"]
        e = (h[0] * h[0] / (ax * ax) + h[1] * h[1] / (ay * ay)) / (h[2] * h[2])
        spec = math.exp(-e) / (4 * PI * ax * ay * math.sqrt(wi[2] * wo[2]))
    else:
        spec = ndf_D(ndf, pn, h) * masking_G(masking, ndf, {**pn, **pm}, wi, wo, h) / (4 * wi[2] * wo[2])
    out = [fresnel_F(fresnel, pf, c, ch) * spec for ch in range(3)]
    if diffuse == "lambert":
        out = [out[ch] + params["diffuse"]["albedo"][ch] / PI for ch in range(3)]
    return tuple(out)


# ---------------------------------------------------------------------------
# The material language (SPEC 1), enough for valid corpus files
# ---------------------------------------------------------------------------

_TOKEN = re.compile(r"""
    (?P<ws>\s+|//[^\n]*|/\*.*?\*/)
  | (?P<num>\d+(?:\.(?!\.)\d*)?(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)
  | (?P<id>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<op>\.\.|[{}(),;=+\-*/^])
""", re.VERBOSE | re.DOTALL)


def tokenize(text):
    pos, out = 0, []
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m:
            raise SyntaxError("cannot lex at offset %d: %r" % (pos, text[pos:pos + 10]))
        pos = m.end()
        if m.lastgroup != "ws":
            out.append((m.lastgroup, m.group()))
    out.append(("end", ""))
    return out


class Parser:
    """Expressions become nested tuples: ('num', v) ('name', n) ('neg', e) (op, a, b) ('call', f, args)."""

    def __init__(self, tokens):
        self.t, self.i = tokens, 0

    def peek(self, k=0):
        return self.t[min(self.i + k, len(self.t) - 1)]

    def take(self, text=None):
        tok = self.t[self.i]
        if text is not None and tok[1] != text:
            raise SyntaxError("expected %r, found %r" % (text, tok[1]))
        self.i += 1
        return tok

    def ident(self):
        tok = self.take()
        if tok[0] != "id":
            raise SyntaxError("expected a name, found %r" % tok[1])
        return tok[1]

    def program(self):
        mats = []
        while self.peek()[0] != "end":
            self.take("material")
            mats.append(self.block())
        return mats

    def block(self):
        """NAME { statements } of a material or (SPEC 10) a lobe -> (name, statements)."""
        name = self.ident()
        self.take("{")
        stmts = []
        while self.peek()[1] != "}":
            stmts.append(self.statement())
        self.take("}")
        return name, stmts

    def statement(self):
        kw = self.ident()
        if kw == "input":
            name = self.ident()
            self.take("=")
            default = self.expr()
            rng = None
            if self.peek()[1] == "in":
                self.take()
                lo = self.expr()
                self.take("..")
                rng = (lo, self.expr())
            self.take(";")
            return ("input", name, default, rng)
        if kw == "let":
            name = self.ident()
            self.take("=")
            e = self.expr()
            self.take(";")
            return ("let", name, e)
        if kw == "lobe":  # SPEC 10: lobe NAME { model statements }
            return ("lobe",) + self.block()
        if kw == "bsdf":  # SPEC 10: bsdf = EXPR; (lobes combined; read by reference_lobes)
            self.take("=")
            e = self.expr()
            self.take(";")
            return ("bsdf", e)
        self.take("=")
        model = self.ident()
        args = self.args() if self.peek()[1] == "(" else []
        self.take(";")
        return ("model", kw, model, args)

    def args(self):
        """'(' [ [NAME '='] expr {',' ...} ] ')' -> list of (name or None, expr)."""
        self.take("(")
        out = []
        if self.peek()[1] == ")":
            self.take()
            return out
        while True:
            name = None
            if self.peek()[0] == "id" and self.peek(1)[1] == "=":
                name = self.take()[1]
                self.take("=")
            out.append((name, self.expr()))
            if self.take()[1] == ")":
                return out

    # Precedence (SPEC 1 plus the mathematical convention): + - < * / < unary - < ^,
    # and ^ is right-associative: -x^2 = -(x^2), 2^3^2 = 2^9.
    def expr(self):
        e = self.term()
        while self.peek()[1] in ("+", "-"):
            op = self.take()[1]
            e = (op, e, self.term())
        return e

    def term(self):
        e = self.unary()
        while self.peek()[1] in ("*", "/"):
            op = self.take()[1]
            e = (op, e, self.unary())
        return e

    def unary(self):
        if self.peek()[1] == "-":
            self.take()
            return ("neg", self.unary())
        return self.power()

    def power(self):
        base = self.primary()
        if self.peek()[1] == "^":
            self.take()
            return ("^", base, self.unary())
        return base

    def primary(self):
        kind, text = self.take()
        if kind == "num":
            return ("num", float(text))
        if kind == "id":
            if self.peek()[1] == "(":
                args = self.args()  # argument names kept for bsdf's layer(.., weight = W)
                return ("call", text, [e for _, e in args], [n for n, _ in args])
            return ("name", text)
        if text == "(":
            e = self.expr()
            self.take(")")
            return e
        raise SyntaxError("expected an expression, found %r" % text)


# Values are floats or 3-tuples (rgb); a float promotes channel-wise.
def _lift(f, *vals):
    if any(isinstance(v, tuple) for v in vals):
        chans = [[v[i] if isinstance(v, tuple) else v for v in vals] for i in range(3)]
        return tuple(f(*c) for c in chans)
    return f(*vals)


FUNCTIONS = {
    "sqrt": math.sqrt,
    "pow": math.pow,
    "exp": math.exp,
    "log": math.log,
    "abs": abs,
    "min": min,
    "max": max,
    "clamp": lambda x, lo, hi: min(max(x, lo), hi),
    "mix": lambda a, b, t: a * (1 - t) + b * t,
    "phong_exponent": lambda r: 2 / r ** 4 - 2,
    "beckmann_to_phong": lambda a: 2 / (a * a) - 2,
}

BINOPS = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": lambda a, b: a / b,
    "^": math.pow,
}


def evaluate(e, env):
    kind = e[0]
    if kind == "num":
        return e[1]
    if kind == "name":
        return env[e[1]]
    if kind == "neg":
        return _lift(lambda x: -x, evaluate(e[1], env))
    if kind == "call":
        args = [evaluate(a, env) for a in e[2]]
        if e[1] == "rgb":
            return tuple(float(a) for a in args)
        return _lift(FUNCTIONS[e[1]], *args)
    return _lift(BINOPS[kind], evaluate(e[1], env), evaluate(e[2], env))


# Model signatures (SPEC 3): each form lists parameter names; "alpha" of the
# one-argument anisotropic NDFs fills both alpha_x and alpha_y.
MODELS = {
    "ndf": {
        "ggx": [["alpha"], ["alpha_x", "alpha_y"]],
        "trowbridge_reitz": [["alpha"], ["alpha_x", "alpha_y"]],
        "beckmann": [["alpha"], ["alpha_x", "alpha_y"]],
        "ward": [["alpha"], ["alpha_x", "alpha_y"]],
        "blinn_phong": [["exponent"]],
        "gtr": [["alpha", "gamma"]],
        "student_t": [["alpha", "gamma"], ["alpha_x", "alpha_y", "gamma"]],
        "gaussian": [["alpha"]],
        "epd": [["alpha", "p"], ["alpha_x", "alpha_y", "p"]],
        "abc": [["b", "c"]],
        "sgd": [["alpha", "p"]],
    },
    "masking": {name: [[]] for name in (
        "none", "implicit", "cook_torrance", "kelemen", "neumann", "smith_separable",
        "smith_height_correlated", "smith_direction_correlated", "smith_height_direction_correlated")},
    "fresnel": {"none": [[]], "schlick": [["f0"], ["eta"]], "dielectric": [["eta"]],
                "conductor": [["eta", "k"]]},
    "diffuse": {"none": [[]], "lambert": [["albedo"]]},
    "energy": {"none": [[]], "kulla_conty": [[]]},
}
MODELS["masking"]["schlick_smith"] = [["k"]]
RGB_SLOTS = ("fresnel", "diffuse")  # their parameters are rgb (a float promotes); ndf and masking take floats


def bind_args(slot, model, args):
    """Matches positional/named arguments to one form; returns {param: expr}."""
    for form in MODELS[slot][model]:
        if len(form) != len(args):
            continue
        bound = {}
        for i, (name, e) in enumerate(args):
            key = name if name is not None else form[i]
            if key not in form or key in bound:
                break
            bound[key] = e
        else:
            return bound
    raise ValueError("arguments of %s %s fit no form" % (slot, model))


def new_models():
    """The model slots of one lobe with their defaults (SPEC 1); ndf None until set."""
    models = {"ndf": None, "masking": "none", "fresnel": "none", "energy": "none", "diffuse": "none"}
    return models, {k: {} for k in models}


def read_model(st, models, model_args):
    _, slot, model, args = st
    if slot in ("scatter", "thin"):  # SPEC 11: a word, read by reference_transmission
        models[slot] = model
        return
    if model == "trowbridge_reitz":
        model = "ggx"  # SPEC 3 alias
    models[slot] = model
    model_args[slot] = bind_args(slot, model, args)


def resolve_models(models, model_args, env):
    """Parameters of every model of one lobe, its expressions evaluated in env."""
    params = {}
    for slot, bound in model_args.items():
        p = {}
        for key, e in bound.items():
            v = evaluate(e, env)
            if slot in RGB_SLOTS:
                p[key] = v if isinstance(v, tuple) else (v, v, v)
            else:
                p[key] = v
        params[slot] = p
    # Canonical NDF parameters; alpha clamped to >= 1e-4 (SPEC 3).
    pn = params["ndf"]
    if models["ndf"] == "sgd":  # alpha clamped to [2e-4, 10], p to [0, 2]
        pn["alpha"] = min(max(pn["alpha"], 2e-4), 10.0)
        pn["p"] = min(max(pn["p"], 0.0), 2.0)
    elif "alpha" in pn:
        pn["alpha"] = max(pn["alpha"], MIN_ALPHA)
        pn.setdefault("alpha_x", pn["alpha"])
        pn.setdefault("alpha_y", pn["alpha"])
    for key in ("alpha_x", "alpha_y"):
        if key in pn:
            pn[key] = max(pn[key], MIN_ALPHA)
    if models["ndf"] == "student_t":  # SPEC 3: gamma > 1.5 (clamped to [1.5, 1e4])
        pn["gamma"] = min(max(pn["gamma"], 1.5), 1e4)
    if models["ndf"] == "epd":  # p clamped to [0.25, 4]
        pn["p"] = min(max(pn["p"], 0.25), 4.0)
    if models["ndf"] == "abc":  # b clamped to [1/8, 2e8], c to [0, 10]
        pn["b"] = min(max(pn["b"], 0.125), 2e8)
        pn["c"] = min(max(pn["c"], 0.0), 10.0)
    return params


class Material:
    def __init__(self, name, stmts):
        self.name = name
        self.inputs = {}   # name -> (default, (lo, hi) or None)
        self.order = []    # ("input"|"let", name, expr) in definition order
        self.models, self.model_args = new_models()  # the implicit lobe of a material without lobe blocks
        self.lobes = {}    # SPEC 10: lobe name -> (models, model_args)
        self.bsdf = None   # SPEC 10: the bsdf expression, None without lobe blocks
        for st in stmts:
            if st[0] == "input":
                _, n, d, rng = st
                dv = evaluate(d, {})
                r = (evaluate(rng[0], {}), evaluate(rng[1], {})) if rng else None
                self.inputs[n] = (dv, r)
                self.order.append(("input", n, None))
            elif st[0] == "let":
                self.order.append(("let", st[1], st[2]))
            elif st[0] == "lobe":
                models, model_args = new_models()
                for inner in st[2]:
                    if inner[0] != "model":
                        raise ValueError("lobe %s: only model statements belong in a lobe" % st[1])
                    read_model(inner, models, model_args)
                self.lobes[st[1]] = (models, model_args)
            elif st[0] == "bsdf":
                self.bsdf = st[1]
            else:
                read_model(st, self.models, self.model_args)
        if self.lobes and self.bsdf is None:
            raise ValueError("material %s has lobes and no bsdf" % name)

    def environment(self, values):
        """Inputs (given values or defaults, clamped to their ranges) and lets, by name."""
        env = {}
        for kind, n, e in self.order:
            if kind == "input":
                default, rng = self.inputs[n]
                v = values.get(n, default)
                if isinstance(default, tuple) and not isinstance(v, tuple):
                    v = (v, v, v)
                if rng:  # out-of-range values are clamped to the range (SPEC 1)
                    v = _lift(lambda x: min(max(x, rng[0]), rng[1]), v)
                env[n] = v
            else:
                env[n] = evaluate(e, env)
        return env

    def resolve(self, values):
        """Parameters of every model for the given input values (missing: defaults)."""
        return resolve_models(self.models, self.model_args, self.environment(values))

    def eval(self, wi, wo, values):
        if self.bsdf is not None:
            return reference_lobes.eval_material(self, wi, wo, values)
        params = self.resolve(values)
        if reference_transmission.whole_sphere(self.models):
            return reference_transmission.bsdf(self.models, params, wi, wo)
        if self.models["energy"] == "kulla_conty":
            return reference_lobes.lobe_value(reference_lobes.ResolvedLobe(self.models, params), wi, wo)
        return brdf(self.models, params, wi, wo)


def load_materials(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    mats = [Material(n, s) for n, s in Parser(tokenize(text)).program()]
    return {m.name: m for m in mats}, [m.name for m in mats]


# ---------------------------------------------------------------------------
# Expect lines
# ---------------------------------------------------------------------------

EXPECT_RE = re.compile(r"^\s*//\s*expect:\s*(?P<args>.*?)\s*->\s*(?P<result>.*?)\s*$")
MATERIAL_RE = re.compile(r"^\s*//\s*material:\s*(?P<name>\S+)\s*$")
_ARG_RE = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(\([^)]*\)|[^\s()]+)")


def parse_number(text):
    v = float(text)
    if not math.isfinite(v):
        raise ValueError("not a finite number: " + text)
    return v


def parse_args(text):
    """'wi=(..) wo=(..) name=v tol=t' -> (wi, wo, values, tol)."""
    wi = wo = None
    tol = DEFAULT_TOL
    values = {}
    pos = 0
    while pos < len(text.rstrip()):
        m = _ARG_RE.match(text, pos)
        if not m:
            raise ValueError("cannot parse %r" % text[pos:])
        pos = m.end()
        key, raw = m.group(1), m.group(2)
        if raw.startswith("("):
            parts = [parse_number(x) for x in raw[1:-1].split(",")]
            if len(parts) != 3:
                raise ValueError("%s needs three components" % key)
            val = tuple(parts)
        else:
            val = parse_number(raw)
        if key == "wi":
            wi = val
        elif key == "wo":
            wo = val
        elif key == "tol":
            tol = val
        else:
            values[key] = val
    if not isinstance(wi, tuple) or not isinstance(wo, tuple):
        raise ValueError("wi=(x,y,z) and wo=(x,y,z) are required")
    return wi, wo, values, tol


def fmt_num(x):
    if x == 0:
        return "0"
    return "%.15g" % x


def fmt_vec(v):
    return "(" + ",".join(fmt_num(x) if x != 0 else "0" for x in v) + ")"


def format_result(rgb):
    txt = [fmt_num(x) for x in rgb]
    return txt[0] if txt[0] == txt[1] == txt[2] else " ".join(txt)


def format_expect(wi, wo, values, tol, rgb):
    parts = ["wi=" + fmt_vec(wi), "wo=" + fmt_vec(wo)]
    for k, v in values.items():
        parts.append("%s=%s" % (k, fmt_vec(v) if isinstance(v, tuple) else fmt_num(v)))
    if tol != DEFAULT_TOL:
        parts.append("tol=%g" % tol)
    return "// expect: " + " ".join(parts) + " -> " + format_result(rgb)


def close(actual, expected, tol):
    if expected == 0:
        return actual == 0
    return abs(actual - expected) <= tol * abs(expected)


def scan(path):
    """Yields (lineno, line, material name, match) for every expect line of a file."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().split("\n")
    current = None
    for no, line in enumerate(lines, 1):
        mm = MATERIAL_RE.match(line)
        if mm:
            current = mm.group("name")
        m = EXPECT_RE.match(line)
        if m:
            yield no, line, current, m


def corpus_files(paths):
    for p in paths:
        if os.path.isdir(p):
            for root, _, files in sorted(os.walk(p)):
                for f in sorted(files):
                    if f.endswith(".mat"):
                        yield os.path.join(root, f)
        else:
            yield p


def compute_line(mats, first, material, m):
    wi, wo, values, tol = parse_args(m.group("args"))
    mat = mats[material or first]
    return wi, wo, values, tol, mat.eval(wi, wo, values)


def cmd_check(paths):
    bad = checked = 0
    default = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "corpus")
    for path in corpus_files(paths or [os.path.normpath(default)]):
        entries = list(scan(path))
        if not entries:
            continue
        try:
            mats, order = load_materials(path)
        except Exception as exc:  # a value file must parse; say which one does not
            print("%s: cannot load: %s" % (path, exc))
            bad += 1
            continue
        for no, line, material, m in entries:
            checked += 1
            try:
                wi, wo, values, tol, rgb = compute_line(mats, order[0], material, m)
                want = [parse_number(x) for x in m.group("result").split()]
                if len(want) == 1:
                    want *= 3
                if len(want) != 3:
                    raise ValueError("expected 1 or 3 result values")
                if not all(close(w, r, tol) for w, r in zip(want, rgb)):
                    print("%s:%d: file says %s, reference gives %s" % (path, no, m.group("result"), format_result(rgb)))
                    bad += 1
            except Exception as exc:
                print("%s:%d: %s" % (path, no, exc))
                bad += 1
    print("%d expect lines checked, %d mismatches" % (checked, bad))
    return 1 if bad else 0


def cmd_update(paths):
    for path in corpus_files(paths):
        entries = list(scan(path))
        if not entries:
            continue
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        # Hand-derived numbers stay as written: --check compares them, --update must not replace them.
        if any(re.match(r"\s*//\s*values:\s*by hand", line) for line in lines):
            print("skipped %s (its values are derived by hand)" % path)
            continue
        mats, order = load_materials(path)
        for no, line, material, m in entries:
            wi, wo, values, tol, rgb = compute_line(mats, order[0], material, m)
            prefix = line[:m.start("result")]
            lines[no - 1] = prefix + format_result(rgb)
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
        print("updated %s (%d expect lines)" % (path, len(entries)))
    return 0


def cmd_eval(argv):
    material = None
    if "--material" in argv:
        i = argv.index("--material")
        material = argv[i + 1]
        del argv[i:i + 2]
    path, rest = argv[0], " ".join(argv[1:])
    mats, order = load_materials(path)
    wi, wo, values, tol = parse_args(rest)
    rgb = mats[material or order[0]].eval(wi, wo, values)
    print(format_expect(wi, wo, values, tol, rgb))
    return 0


def cmd_selftest():
    """Checks of this script against facts independent of any corpus file."""
    fails = 0

    def check(what, got, want, rel=1e-12):
        nonlocal fails
        ok = abs(got - want) <= rel * abs(want)
        print("%-60s %s  (got %.17g, want %.17g)" % (what, "ok" if ok else "FAIL", got, want))
        fails += not ok

    check("Int_0^pi sin", integrate(math.sin, 0, PI), 2.0)
    check("Int_0^1 exp", integrate(math.exp, 0, 1), math.e - 1)
    # Small alpha: cos t sin t = t - 2t^3/3 + 2t^5/15 - ..., and Int_0^inf t^(2j+1) exp(-t^2/a^2) dt
    # = j! a^(2j+2) / 2, so N = pi a^2 (1 - 2a^2/3 + 4a^4/15 - 8a^6/105 + O(a^8)).
    for a in (1e-3, 0.01, 0.03):
        series = PI * a * a * (1 - 2 * a * a / 3 + 4 * a ** 4 / 15 - 8 * a ** 6 / 105)
        check("gaussian N(%g) vs series" % a, gaussian_norm(a), series, 1e-12)

    # Every NDF except ward: Int D(m) cos(theta_m) dw = 1 (SPEC 3), by a 2-D quadrature.
    def projected_area(ndf, p):
        def over_theta(t):
            def over_phi(ph):
                m = (math.sin(t) * math.cos(ph), math.sin(t) * math.sin(ph), math.cos(t))
                return ndf_D(ndf, p, m)
            return integrate(over_phi, 0, 2 * PI, 1e-11) * math.cos(t) * math.sin(t)
        return integrate(over_theta, 0, PI / 2, 1e-10)

    cases = [("ggx", {"alpha_x": 0.3, "alpha_y": 0.3}), ("ggx", {"alpha_x": 0.2, "alpha_y": 0.6}),
             ("beckmann", {"alpha_x": 0.4, "alpha_y": 0.25}), ("blinn_phong", {"exponent": 30.0}),
             ("gtr", {"alpha": 0.4, "gamma": 1.0}), ("gtr", {"alpha": 0.4, "gamma": 2.5}),
             ("gtr", {"alpha": 1.0, "gamma": 3.0}), ("gaussian", {"alpha": 0.3}),
             ("epd", {"alpha_x": 0.3, "alpha_y": 0.3, "p": 0.6}), ("epd", {"alpha_x": 0.2, "alpha_y": 0.5, "p": 2.0}),
             ("abc", {"b": 20.0, "c": 1.5}), ("abc", {"b": 0.5, "c": 0.0}), ("abc", {"b": 300.0, "c": 2.0}),
             ("sgd", {"alpha": 0.1, "p": 0.6}), ("sgd", {"alpha": 0.05, "p": 1.0}), ("sgd", {"alpha": 2.0, "p": 2.0})]
    for ndf, p in cases:
        check("normalization %s %s" % (ndf, p), projected_area(ndf, p), 1.0, 1e-8)
    # The Smith Lambda by quadrature (used for the NDFs without a closed form)
    # reproduces the closed forms of ggx and beckmann, isotropic and not.
    for ndf, p in (("ggx", {"alpha_x": 0.3, "alpha_y": 0.3}), ("beckmann", {"alpha_x": 0.2, "alpha_y": 0.5})):
        for theta, phi in ((0.5, 0.0), (1.2, 0.7), (1.5706, 2.0)):
            v = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))
            closed = smith_lambda(ndf, p, v)
            check("Lambda by quadrature = closed form, %s theta=%g" % (ndf, theta),
                  lambda_by_quadrature(ndf, p, v), closed, 1e-11)
    # Conductor with k = 0 is a dielectric (two independent formulas).
    for c in (0.05, 0.4, 0.9, 1.0):
        check("conductor(k=0) = dielectric at c=%g" % c, fresnel_conductor(c, 1.7, 0.0), fresnel_dielectric(c, 1.7))
    # The real-arithmetic conductor form against the textbook complex one:
    # N cos(t) = sqrt(N^2 - sin^2), rs = (c - N cos t)/(c + N cos t), rp = (N^2 c - N cos t)/(N^2 c + N cos t).
    for c in (0.05, 0.4, 0.9, 1.0):
        n = complex(0.2, 3.0)
        nct = cmath.sqrt(n * n - (1 - c * c))
        rs, rp = (c - nct) / (c + nct), (n * n * c - nct) / (n * n * c + nct)
        check("conductor real form = complex form at c=%g" % c, fresnel_conductor(c, 0.2, 3.0),
              (abs(rs) ** 2 + abs(rp) ** 2) / 2)
    import reference_lobes_selftest  # SPEC 10: albedo quadrature, Kulla-Conty, the layer
    reference_lobes_selftest.selftest(check)
    print("selftest: %s" % ("FAILED" if fails else "passed"))
    return 1 if fails else 0


# The multi-lobe part (SPEC 10) lives in its own module; it imports this one by
# name, so a run as a script registers this module under that name first (one
# copy of the caches and classes, not two).
sys.modules.setdefault("reference_values", sys.modules[__name__])
import reference_lobes  # noqa: E402  (needs the definitions above)
import reference_transmission  # noqa: E402  (SPEC 11; needs the definitions above)


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "--check":
        return cmd_check(rest)
    if cmd == "--update":
        return cmd_update(rest)
    if cmd == "--eval":
        return cmd_eval(rest)
    if cmd == "--selftest":
        return cmd_selftest()
    print("unknown command %r; see --help" % cmd, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
