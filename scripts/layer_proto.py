#!/usr/bin/python3
"""Facet layer(TOP, BASE) prototype: reciprocal, energy-bounded albedo scaling.

    f_layer(wi, wo) = f_top(wi, wo) + S(wi, wo) * f_base(wi, wo)

Self-contained (numpy + scipy.special.erfc).  Run with /usr/bin/python3:

    /usr/bin/python3 layer_proto.py            # checks + reciprocity + energy table (~0.5-1 min)
    /usr/bin/python3 layer_proto.py --extra    # + base-with-Fresnel and other-top checks (~3 min)
    /usr/bin/python3 layer_proto.py --check    # quadrature checks only
    /usr/bin/python3 layer_proto.py --nmu 33   # mu table resolution (--map sqrt: other mapping)
    /usr/bin/python3 layer_proto.py --params   # multi-D (alpha_top, eta, alpha_base) tables (~5 min)

Conventions: n = +z; mu = n.w; wo = (sin_o, 0, mu_o).  All lobes are isotropic.
Tables over mu: nodes uniform in x, mu = (exp(6x)-1)/(exp(6)-1) (or x^2 with --map sqrt),
linear interpolation in x (as the C++ side would bake them), node 0 evaluated at mu = MU_MIN.

Candidate S (u(mu) = 1 - E_top(mu), all per channel):
  onesided   S = u_o                                   (OpenPBR / MaterialX; not reciprocal)
  product    S = u_i u_o
  prod_avg   S = u_i u_o / (1 - Ebar_top)
  sqrt_T     S = u_i u_o / sqrt(T_b(mu_i) T_b(mu_o))
  max_T      S = u_i u_o / max(T_b(mu_i), T_b(mu_o))   (provably <= 1, but loses up to ~6%)
  balanced   S = g_b(mu_i) g_b(mu_o)                  <- chosen; one table g_b(mu) solving
                                                          g(o) int g(mu_i) f_b mu_i dwi = u(o) A_b(o)
  balanced_uh  same, with u and h_b = g_b/u interpolated separately
  hybrid     S = u_i u_o min(h_i h_o, 1/max(T_i, T_o)) (balanced, capped by the provable max_T bound)
with T_b(mu_o) = int u(mu_i) f_b(wi,wo) mu_i dwi / int f_b(wi,wo) mu_i dwi.
"""
import argparse
import sys
import time

import numpy as np
from numpy.polynomial.legendre import leggauss
from scipy.special import erfc

MU_MIN = 1e-4
NU, NPHI = 96, 32          # Gauss-Legendre points per u-interval (2 intervals) and in phi
NLAM = 128                 # Gauss-Legendre points for cosine-weighted hemisphere (in sqrt(mu))

# ----------------------------------------------------------------------------- microfacet parts


def smith_lambda(mu, ndf, a):
    """Smith Lambda for isotropic GGX / Beckmann; mu = n.v (clamped to (0, 1])."""
    mu = np.clip(mu, 1e-300, 1.0)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        t = np.sqrt(np.maximum(1.0 - mu * mu, 0.0)) / mu          # tan(theta)
        if ndf == 'ggx':
            x = (a * t) ** 2
            L = x / (2.0 * (1.0 + np.sqrt(1.0 + x)))
            return np.where(np.isfinite(L), L, 1e300)
        b = 1.0 / (a * t)
        L = 0.5 * (np.exp(-b * b) / (b * np.sqrt(np.pi)) - erfc(b))
        return np.where(np.isfinite(b), L, 0.0)


def ndf_D(cos_h, ndf, a):
    c2 = cos_h * cos_h
    t2 = np.maximum(1 - c2, 0) / c2
    if ndf == 'ggx':
        return 1.0 / (np.pi * a * a * c2 * c2 * (1 + t2 / (a * a)) ** 2)
    return np.exp(-t2 / (a * a)) / (np.pi * a * a * c2 * c2)


def G2_hc(mui, muo, ndf, a):
    """Height-correlated Smith (chi+ handled by the caller's domain)."""
    return 1.0 / (1.0 + smith_lambda(mui, ndf, a) + smith_lambda(muo, ndf, a))


def fresnel(c, fr):
    """fr = None (F=1) | ('dielectric', eta) | ('schlick', f0).  c = wo.h = wi.h > 0."""
    if fr is None:
        return np.ones_like(c)
    kind, p = fr
    if kind == 'schlick':
        return p + (1 - p) * (1 - c) ** 5
    eta = p
    g2 = eta * eta - 1 + c * c
    g = np.sqrt(np.maximum(g2, 0))
    A = (g - c) / (g + c)
    B = (c * (g + c) - 1) / (c * (g - c) + 1)
    return np.where(g2 > 0, 0.5 * A * A * (1 + B * B), 1.0)


def _cdf_theta(th, ndf, a):
    t2 = np.tan(th) ** 2 / (a * a)
    return t2 / (1 + t2) if ndf == 'ggx' else -np.expm1(-t2)


def _tan_of_u(u, ndf, a):
    with np.errstate(divide='ignore', invalid='ignore'):
        return a * (np.sqrt(u / (1 - u)) if ndf == 'ggx' else np.sqrt(-np.log1p(-u)))


def microfacet_points(mu_o, ndf, a, fr=None, nu=NU, nphi=NPHI):
    """Quadrature of int g(wi) f(wi,wo) mu_i dwi for a microfacet lobe
        f = D G2 F / (4 mu_i mu_o)
    over the half vector, importance-sampled by construction:  u = CDF of D(h)(n.h) in
    theta_h (D cos dw = du dphi / 2pi), so narrow lobes are resolved at any alpha.
    The visible domain (mu_i > 0) is theta_h < pi/4 + theta_o/2, and for theta_h <
    pi/4 - theta_o/2 all phi are visible, so u is split there (no discontinuity inside an
    interval) and phi runs over [0, phi_max(theta_h)] (times 2 by symmetry); the second u
    interval is clustered at its upper end ((1-s)^2 map) to absorb the 1/cos(theta_h)
    growth of GGX's tail at grazing wo.
    Returns mu_i, w, c=wo.h with shape (len(mu_o), 2*nu*nphi):
        int g f mu_i dwi ~= sum_q w_q g(mu_i_q)."""
    mu_o = np.atleast_1d(np.asarray(mu_o, float))[:, None]
    so = np.sqrt(np.maximum(1 - mu_o * mu_o, 0))
    tho = np.arctan2(so, mu_o)
    u1 = _cdf_theta(np.pi / 4 - tho / 2, ndf, a)
    u2 = _cdf_theta(np.pi / 4 + tho / 2, ndf, a)
    x, wx = leggauss(nu)
    s = 0.5 * (x + 1)
    ws = 0.5 * wx
    ua, wa = u1 * s, u1 * ws
    ub, wb = u2 - (u2 - u1) * (1 - s) ** 2, (u2 - u1) * 2 * (1 - s) * ws
    u = np.concatenate([ua, ub], axis=1)        # (m, 2nu)
    wu = np.concatenate([wa, wb], axis=1)
    t = _tan_of_u(u, ndf, a)
    ch = 1 / np.sqrt(1 + t * t)
    sh = t * ch
    with np.errstate(divide='ignore', invalid='ignore'):
        cs = -mu_o * (ch * ch - sh * sh) / (so * 2 * sh * ch)
    cs = np.nan_to_num(cs, nan=-1.0, posinf=2.0, neginf=-2.0)
    pm = np.arccos(np.clip(cs, -1, 1))          # phi_max
    xp, wp = leggauss(nphi)
    phi = pm[..., None] * (xp + 1) / 2           # (m, 2nu, nphi)
    w = (wu * pm / (2 * np.pi))[..., None] * wp
    chh, shh = ch[..., None], sh[..., None]
    muo3 = mu_o[..., None]
    c = so[..., None] * shh * np.cos(phi) + muo3 * chh
    mui = 2 * c * chh - muo3
    ok = (mui > 0) & (w > 0)
    mui_s = np.where(ok, mui, 0.5)
    val = c / (muo3 * chh) * G2_hc(mui_s, muo3, ndf, a) * fresnel(np.where(ok, c, 1.0), fr)
    w = np.where(ok, w * val, 0.0)
    m = mu_o.shape[0]
    return mui_s.reshape(m, -1), w.reshape(m, -1), c.reshape(m, -1)


def lambert_points(n=NLAM):
    """int g(mu_i) (1/pi) mu_i dwi = int_0^1 g 2 mu dmu, GL in x = sqrt(mu)."""
    x, wx = leggauss(n)
    x = 0.5 * (x + 1)
    wx = 0.5 * wx
    return x * x, 4 * x ** 3 * wx


# ----------------------------------------------------------------------------- lobes


class Lobe:
    """kind = 'lambert' | 'ggx' | 'beckmann'; fr = Fresnel; kc = add Kulla-Conty f_ms (F=1)."""

    def __init__(self, kind, alpha=None, fr=None, kc=False, albedo=1.0):
        self.kind, self.alpha, self.fr, self.kc, self.albedo = kind, alpha, fr, kc, albedo
        if kc:
            self.lm, self.lw = lambert_points()
            self.Eb_l = microfacet_points(self.lm, kind, alpha)[1].sum(1)   # E_b(mu) F=1
            self.Ebar = np.sum(self.lw * self.Eb_l)

    def name(self):
        if self.kind == 'lambert':
            return 'lambert' if self.albedo == 1 else 'lambert%.2f' % self.albedo
        s = '%s a=%g' % (self.kind, self.alpha)
        if self.fr is not None:
            s += ' %s%g' % self.fr
        return s + (' +KC' if self.kc else '')

    def points(self, mu_o):
        """(mu_i, w) with int g f mu_i dwi ~= sum w g(mu_i); shape (len(mu_o), Q)."""
        mu_o = np.atleast_1d(np.asarray(mu_o, float))
        if self.kind == 'lambert':
            m, w = lambert_points()
            return np.broadcast_to(m, (len(mu_o), len(m))), \
                np.broadcast_to(self.albedo * w, (len(mu_o), len(m)))
        mi, w, _ = microfacet_points(mu_o, self.kind, self.alpha, self.fr)
        if self.kc:
            Eo = microfacet_points(mu_o, self.kind, self.alpha)[1].sum(1)
            wk = self.lw[None, :] * (1 - self.Eb_l)[None, :] * (1 - Eo)[:, None] / (1 - self.Ebar)
            mi = np.concatenate([mi, np.broadcast_to(self.lm, (len(mu_o), len(self.lm)))], 1)
            w = np.concatenate([w, wk], 1)
        return mi, w

    def eval(self, wi, wo):
        """BRDF value (no cosine) for direction arrays (..., 3)."""
        mui, muo = wi[..., 2], wo[..., 2]
        if self.kind == 'lambert':
            return np.where((mui > 0) & (muo > 0), self.albedo / np.pi, 0.0)
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        c = np.sum(wi * h, -1)
        f = ndf_D(h[..., 2], self.kind, self.alpha) * G2_hc(mui, muo, self.kind, self.alpha) \
            * fresnel(c, self.fr) / (4 * mui * muo)
        return np.where((mui > 0) & (muo > 0), f, 0.0)


def albedo(lobe, mu):
    return lobe.points(mu)[1].sum(1)


# ----------------------------------------------------------------------------- tables


class Grid:
    """Tables over mu: nodes uniform in x, mu = map(x), linear interpolation in x.
    'log': mu = (exp(K x) - 1)/(exp(K) - 1), K = 6 (dense at grazing, where E_top of a
    near-specular top has its shadowing / Fresnel knee at mu ~ alpha); 'sqrt': mu = x^2."""
    K = 6.0

    def __init__(self, n, mapping='log'):
        self.n, self.mapping = n, mapping
        self.x = np.linspace(0, 1, n)
        self.mu = np.maximum(self.fwd(self.x), MU_MIN)

    def fwd(self, x):
        if self.mapping == 'sqrt':
            return x * x
        return np.expm1(self.K * x) / np.expm1(self.K)

    def inv(self, mu):
        mu = np.clip(mu, 0, 1)
        if self.mapping == 'sqrt':
            return np.sqrt(mu)
        return np.log1p(mu * np.expm1(self.K)) / self.K

    def interp(self, table, mu):
        return np.interp(self.inv(mu), self.x, table)

    def matrix(self, mui, w):
        """M[j,k]: sum_q w_jq * hat_k(mu_i,jq)  -> (M g)_j = int g(interp) f mu_i dwi at node j."""
        n = self.n
        p = self.inv(mui) * (n - 1)
        k = np.minimum(np.floor(p).astype(int), n - 2)
        fr = p - k
        rows = np.broadcast_to(np.arange(mui.shape[0])[:, None], mui.shape)
        M = np.bincount((rows * n + k).ravel(), (w * (1 - fr)).ravel(), n * n) + \
            np.bincount((rows * n + k + 1).ravel(), (w * fr).ravel(), n * n)
        return M.reshape(n, n)


class BaseData:
    """Everything about a base lobe that does not depend on the top."""

    def __init__(self, lobe, grid, mu_test, weight_lobe=None):
        # weight_lobe: lobe used to build T_b / h tables (surrogate, e.g. F=1 when the base
        # has a Fresnel); default: the base itself.
        self.lobe, self.grid, self.mu_test = lobe, grid, mu_test
        wl = weight_lobe or lobe
        self.M = grid.matrix(*wl.points(grid.mu))
        self.A_nodes = self.M.sum(1)
        self.mi_t, self.w_t = lobe.points(mu_test)           # test quadrature, true base
        self.A_test = self.w_t.sum(1)


class TopData:
    def __init__(self, lobe, grid, mu_test):
        self.lobe, self.grid = lobe, grid
        self.E_nodes = albedo(lobe, grid.mu)
        self.E_true_test = albedo(lobe, mu_test)
        lm, lw = lambert_points()
        self.Ebar = np.sum(lw * grid.interp(self.E_nodes, lm))
        self.u_nodes = 1 - self.E_nodes

    def u(self, mu):
        return 1 - self.grid.interp(self.E_nodes, mu)


SINKHORN_ITERS = [0]


def sinkhorn(M, A, u, iters=5000, tol=1e-12):
    """Symmetric matrix balancing: find h > 0 with h * (M (u h)) = A on the nodes.
    Start from h = 1/sqrt(T_b) (exact for a Lambert base); damped (geometric-mean)
    symmetric Sinkhorn step h <- sqrt(h * A / M(u h))."""
    h = 1 / np.sqrt(np.maximum(M @ u / A, 1e-12))
    for it in range(iters):
        g = M @ (u * h)
        hn = np.sqrt(h * A / np.maximum(g, 1e-300))
        if np.max(np.abs(hn / h - 1)) < tol:
            break
        h = hn
    SINKHORN_ITERS[0] = max(SINKHORN_ITERS[0], it + 1)
    return hn


T_FLOOR = 1e-6


class Pair:
    """Tables for one (top, base) pair and the candidate S functions."""

    def __init__(self, top, base):
        self.top, self.base, g = top, base, top.grid
        self.T_nodes = np.maximum(base.M @ top.u_nodes / base.A_nodes, T_FLOOR)
        self.h_nodes = sinkhorn(base.M, base.A_nodes, top.u_nodes)
        self.g_nodes = top.u_nodes * self.h_nodes

    def T(self, mu):
        return self.top.grid.interp(self.T_nodes, mu)

    def h(self, mu):
        return self.top.grid.interp(self.h_nodes, mu)

    def S(self, name, mui, muo):
        t = self.top
        ui, uo = t.u(mui), t.u(muo)
        if name == 'onesided':
            return uo + 0 * ui
        if name == 'product':
            return ui * uo
        if name == 'prod_avg':
            return ui * uo / (1 - t.Ebar)
        if name == 'sqrt_T':
            return ui * uo / np.sqrt(self.T(mui) * self.T(muo))
        if name == 'max_T':
            return ui * uo / np.maximum(self.T(mui), self.T(muo))
        if name == 'balanced':       # chosen: single table g = u h, S = g(mu_i) g(mu_o)
            return self.top.grid.interp(self.g_nodes, mui) * self.top.grid.interp(self.g_nodes, muo)
        if name == 'balanced_uh':    # same h, but u and h interpolated separately
            return ui * uo * self.h(mui) * self.h(muo)
        if name == 'hybrid':
            return ui * uo * np.minimum(self.h(mui) * self.h(muo),
                                        1 / np.maximum(self.T(mui), self.T(muo)))
        raise ValueError(name)

    def totals(self, name, W=1.0):
        """Total directional albedo at the test mu_o's (true E_top, tabulated S).
        Weighted layer: W f_top + (1 - W + W S) f_base."""
        b, muo = self.base, self.base.mu_test[:, None]
        S = self.S(name, b.mi_t, muo)
        SW = 1 - W + W * S
        return W * self.top.E_true_test + np.sum(b.w_t * SW, 1)


CANDIDATES = ['onesided', 'product', 'prod_avg', 'sqrt_T', 'max_T', 'balanced_uh', 'hybrid', 'balanced']
ALPHAS_TOP = [0.01, 0.05, 0.1, 0.3, 0.6, 1.0]
ETAS = [1.05, 1.33, 1.5, 2.0, 3.0]
MU_TEST = np.array([0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6,
                    0.7, 0.8, 0.9, 0.99, 1.0])


def bases():
    out = [Lobe('lambert')]
    for ndf in ['ggx', 'beckmann']:
        for a in [0.01, 0.1, 0.3, 1.0]:
            out.append(Lobe(ndf, a))
    for a in [0.1, 0.3, 1.0]:
        out.append(Lobe('ggx', a, kc=True))   # white-furnace-compensated base, A_b ~ 1
    return out


# ----------------------------------------------------------------------------- checks


def quadrature_checks():
    print('== quadrature checks (F=1, height-correlated Smith) ==')
    print('E(mu=1, GGX alpha=0.5)  :', [round(float(microfacet_points([1.0], 'ggx', 0.5, None, n, p)[1].sum()), 8)
                                        for n, p in ((24, 8), (48, 16), (96, 32), (192, 64))])
    print('E(mu=1, GGX alpha=0.25) :', round(float(albedo(Lobe('ggx', 0.25), [1.0])[0]), 6))
    # independent brute force over wi (GL in mu_i x phi_i) for rough lobes
    def brute(mu_o, ndf, a, n=600):
        x, wx = leggauss(n); mi = 0.5 * (x + 1); wm = 0.5 * wx
        xp, wp = leggauss(2 * n); ph = np.pi * 0.5 * (xp + 1); wph = np.pi * wp
        MI, PH = np.meshgrid(mi, ph, indexing='ij')
        si = np.sqrt(1 - MI ** 2)
        wi = np.stack([si * np.cos(PH), si * np.sin(PH), MI], -1)
        wo = np.broadcast_to(np.array([np.sqrt(1 - mu_o ** 2), 0, mu_o]), wi.shape)
        return np.sum(np.outer(wm, wph) * Lobe(ndf, a).eval(wi, wo) * MI)
    print('half-vector quadrature vs brute force over wi (rough lobes):')
    for ndf in ['ggx', 'beckmann']:
        for a, m in [(0.5, 1.0), (0.5, 0.3), (1.0, 0.05), (0.3, 0.7)]:
            e = albedo(Lobe(ndf, a), [m])[0]
            print('  %-8s a=%-4g mu=%-5g  E=%.7f  brute=%.7f' % (ndf, a, m, e, brute(m, ndf, a)))
    print('Smith Lambda vs its definition (1+Lambda(v)) mu_v = int D(m) (v.m)+ dm (brute force):')
    for ndf in ['ggx', 'beckmann']:
        for a, mu in [(0.3, 0.2), (1.0, 0.5), (0.1, 0.05)]:
            x, wx = leggauss(4000); u = 0.5 * (x + 1); wu = 0.5 * wx
            t = _tan_of_u(u, ndf, a); ch = 1 / np.sqrt(1 + t * t); sh = t * ch
            xp, wp = leggauss(400); ph = np.pi * 0.5 * (xp + 1); wph = 0.5 * wp   # phi in [0,pi], /2pi *2
            vm = np.sqrt(1 - mu * mu) * sh[:, None] * np.cos(ph) + mu * ch[:, None]
            lhs = np.sum(np.outer(wu, wph) * np.maximum(vm, 0) / ch[:, None])
            print('  %-8s a=%-4g mu=%-5g  (1+L)mu=%.7f  int=%.7f' %
                  (ndf, a, mu, (1 + smith_lambda(np.array(mu), ndf, a)) * mu, lhs))
    print('doubling (NU,NPHI) -> (2NU,2NPHI), narrow and grazing lobes, eta=1.5 / F=1:')
    worst = 0
    for ndf in ['ggx', 'beckmann']:
        for a in ALPHAS_TOP:
            for fr in [None, ('dielectric', 1.5), ('dielectric', 3.0)]:
                mu = MU_TEST
                e1 = microfacet_points(mu, ndf, a, fr)[1].sum(1)
                e2 = microfacet_points(mu, ndf, a, fr, 2 * NU, 2 * NPHI)[1].sum(1)
                worst = max(worst, np.max(np.abs(e1 - e2)))
    print('  max |E(NU,NPHI) - E(2NU,2NPHI)| over all tops x mu_test: %.2e' % worst)
    lm, lw = lambert_points()
    print('  Lambert quadrature sum of weights: %.15f' % lw.sum())


def reciprocity_check(grid, rng=np.random.default_rng(1)):
    """Evaluate full f_layer(wi,wo) and f_layer(wo,wi) at random directions."""
    worst = {}
    for top_l, base_l in [(Lobe('ggx', 0.1, ('dielectric', 1.5)), Lobe('ggx', 0.3)),
                          (Lobe('beckmann', 0.3, ('dielectric', 2.0)), Lobe('lambert')),
                          (Lobe('ggx', 0.01, ('dielectric', 1.5)), Lobe('beckmann', 0.1))]:
        top = TopData(top_l, grid, MU_TEST)
        base = BaseData(base_l, grid, MU_TEST)
        pr = Pair(top, base)
        n = 20000
        def rand_dir():
            mu = rng.uniform(0.001, 1, n); ph = rng.uniform(0, 2 * np.pi, n)
            s = np.sqrt(1 - mu * mu)
            return np.stack([s * np.cos(ph), s * np.sin(ph), mu], -1)
        wi, wo = rand_dir(), rand_dir()
        for name in CANDIDATES:
            f1 = top_l.eval(wi, wo) + pr.S(name, wi[:, 2], wo[:, 2]) * base_l.eval(wi, wo)
            f2 = top_l.eval(wo, wi) + pr.S(name, wo[:, 2], wi[:, 2]) * base_l.eval(wo, wi)
            rel = np.max(np.abs(f1 - f2) / np.maximum(np.abs(f1) + np.abs(f2), 1e-30))
            worst[name] = max(worst.get(name, 0), rel)
    print('== reciprocity: max |f(wi,wo)-f(wo,wi)| / (|f(wi,wo)|+|f(wo,wi)|), 60000 random pairs ==')
    for k, v in worst.items():
        print('  %-9s %.2e' % (k, v))


# ----------------------------------------------------------------------------- main table


def _acc(st, key, arr, where):
    i = int(np.argmax(arr))
    if arr[i] > st.get(key, -9):
        st[key] = float(arr[i])
        st['at_' + key] = where + (float(MU_TEST[i]),)


def run(nmu, mapping, chosen='balanced'):
    grid = Grid(nmu, mapping)
    t0 = time.time()
    B = [BaseData(b, grid, MU_TEST) for b in bases()]
    stats = {c: {b.lobe.name(): {} for b in B} for c in CANDIDATES}
    WS = [0.0, 0.25, 0.5, 0.75, 1.0]
    wstats = {W: {} for W in WS}
    sanity = {}
    for a in ALPHAS_TOP:
        for eta in ETAS:
            top = TopData(Lobe('ggx', a, ('dielectric', eta)), grid, MU_TEST)
            for b in B:
                pr = Pair(top, b)
                ref = top.E_true_test + (1 - top.E_true_test) * b.A_test   # one-sided target
                for c in CANDIDATES:
                    tot = pr.totals(c)
                    st = stats[c][b.lobe.name()]
                    norm = top.E_true_test + (tot - top.E_true_test) / b.A_test  # base rescaled to A_b=1
                    for key, arr in (('gain', tot - 1), ('loss', 1 - tot), ('lam', np.abs(tot - 1)),
                                     ('dev_hi', tot - ref), ('dev_lo', ref - tot), ('ngain', norm - 1)):
                        _acc(st, key, arr, (a, eta))
                    if a == 0.01 and eta == 1.5 and b.lobe.name() in ('lambert', 'ggx a=0.01'):
                        sanity[(c, b.lobe.name())] = tot[-1]      # mu_o = 1
                for W in WS:
                    tot = pr.totals(chosen, W)
                    _acc(wstats[W], 'gain', tot - 1, (a, eta))
                    if b.lobe.kind == 'lambert':
                        _acc(wstats[W], 'lam', np.abs(tot - 1), (a, eta))
    print('\n== energy table: top = GGX(alpha_top) + dielectric(eta); alpha_top in %s; eta in %s'
          % (ALPHAS_TOP, ETAS))
    print('   mu_o in %s' % list(MU_TEST))
    print('   mu tables: %d nodes, mapping %s; %.0f s; max Sinkhorn iterations %d ==' %
          (nmu, mapping, time.time() - t0, SINKHORN_ITERS[0]))
    print('   gain  = max(total - 1)                         requirement 2: <= 1e-3')
    print('   ngain = max(total with the base rescaled to A_b(o) = 1, minus 1): worst case of any base of this shape')
    print('   |L-1| = max |total - 1| for the white Lambert base   requirement 3: <= 1e-3')
    print('   dev+/dev- = max excess / deficit of total vs E_o + (1 - E_o) A_b(o) (one-sided albedo scaling)')
    for c in CANDIDATES:
        print('\n-- S = %s' % c)
        print('   %-16s %9s %9s %9s %9s %9s   %-22s %s' %
              ('base', 'gain', 'ngain', '|L-1|', 'dev+', 'dev-', 'worst ngain at', 'worst dev- at'))
        print('   %-16s %9s %9s %9s %9s %9s   %-22s %s' % ('', '', '', '', '', '', '(a_top, eta, mu_o)', ''))
        for b in B:
            st = stats[c][b.lobe.name()]
            lam = '%9.2e' % st['lam'] if b.lobe.kind == 'lambert' else '%9s' % '-'
            print('   %-16s %9.2e %9.2e %s %9.2e %9.2e   %-22s %s' %
                  (b.lobe.name(), st['gain'], st['ngain'], lam, st['dev_hi'], st['dev_lo'],
                   st['at_ngain'], st['at_dev_lo']))
    print('\n== sanity (alpha_top = 0.01, eta = 1.5, mu_o = 1) ==')
    print('   product  S = u_i u_o         over white Lambert: total = %.4f (loss %.1f%%)' %
          (sanity[('product', 'lambert')], 100 * (1 - sanity[('product', 'lambert')])))
    print('   prod_avg S = u_i u_o/(1-Ebar) over white GGX a=0.01: total = %.4f (gain %.1f%%)' %
          (sanity[('prod_avg', 'ggx a=0.01')], 100 * (sanity[('prod_avg', 'ggx a=0.01')] - 1)))
    print('\n== weighted form (%s): f = W f_top + (1 - W + W S) f_base, all bases above ==' % chosen)
    for W in WS:
        print('   W=%.2f  max(total-1) %9.2e   white Lambert max|total-1| %9.2e' %
              (W, wstats[W]['gain'], wstats[W]['lam']))
    return stats


def fresnel_base_check(nmu, mapping, cands=('balanced', 'hybrid', 'max_T')):
    """Base with its own Fresnel; tables h_b / T_b built from the F=1 base (surrogate)."""
    grid = Grid(nmu, mapping)
    print('\n== base with its own Fresnel; h_b/T_b tables from the same base with F = 1 (surrogate) ==')
    print('   max over all GGX tops of the main grid; gain = max(total-1), ngain as above, dev = |total - one-sided|')
    print('   %-32s' % 'base' + ''.join('%27s' % c for c in cands))
    print('   %-32s' % '' + ''.join('%9s%9s%9s' % ('gain', 'ngain', 'dev') for c in cands))
    tops = [TopData(Lobe('ggx', at, ('dielectric', eta)), grid, MU_TEST) for at in ALPHAS_TOP for eta in ETAS]
    for ndf in ['ggx', 'beckmann']:
        for a in [0.01, 0.3, 1.0]:
            for fr in [('schlick', 0.04), ('schlick', 0.5), ('schlick', 0.95), ('dielectric', 1.5)]:
                bl = Lobe(ndf, a, fr)
                bs = BaseData(bl, grid, MU_TEST, weight_lobe=Lobe(ndf, a))
                r = {c: [-9, -9, -9] for c in cands}
                for top in tops:
                    pr = Pair(top, bs)
                    ref = top.E_true_test + (1 - top.E_true_test) * bs.A_test
                    for c in cands:
                        tot = pr.totals(c)
                        norm = top.E_true_test + (tot - top.E_true_test) / bs.A_test
                        r[c] = [max(r[c][0], np.max(tot - 1)), max(r[c][1], np.max(norm - 1)),
                                max(r[c][2], np.max(np.abs(tot - ref)))]
                print('   %-32s' % bl.name() + ''.join('%9.2e%9.2e%9.2e' % tuple(r[c]) for c in cands))


def other_tops_check(nmu, mapping, cands=('balanced', 'hybrid', 'max_T')):
    """Beckmann tops, and absorbing (Schlick f0, conductor-like) tops, one channel each."""
    grid = Grid(nmu, mapping)
    B = [BaseData(b, grid, MU_TEST) for b in bases()]
    print('\n== other tops (max over all bases of the main table) ==')
    print('   %-30s' % 'top' + ''.join('%27s' % c for c in cands))
    print('   %-30s' % '' + ''.join('%9s%9s%9s' % ('gain', 'ngain', '|L-1|') for c in cands))
    for tl in [Lobe('beckmann', a, ('dielectric', e)) for a in (0.01, 0.1, 0.3, 1.0) for e in (1.05, 1.5, 3.0)] + \
              [Lobe('ggx', a, ('schlick', f0)) for a in (0.01, 0.1, 0.5) for f0 in (0.02, 0.3, 0.9)]:
        top = TopData(tl, grid, MU_TEST)
        r = {c: [-9, -9, -9] for c in cands}
        for b in B:
            pr = Pair(top, b)
            for c in cands:
                tot = pr.totals(c)
                norm = top.E_true_test + (tot - top.E_true_test) / b.A_test
                r[c][0] = max(r[c][0], np.max(tot - 1)); r[c][1] = max(r[c][1], np.max(norm - 1))
                if b.lobe.kind == 'lambert':
                    r[c][2] = np.max(np.abs(tot - 1))
        print('   %-30s' % tl.name() + ''.join('%9.2e%9.2e%9.2e' % tuple(r[c]) for c in cands))


def param_interp_check(nmu, mapping, n_alpha=64, n_eta=32, alpha_nodes='log', eta_nodes='log_eta_m1',
                       modes=('alpha', 'eta', 'base', 'all')):
    """Multi-D tables g(mu; alpha_top, eta, alpha_base) (and E_top(mu; alpha_top, eta) for a
    Lambert base): bake at parameter nodes, query mid-cell (multilinear = average of the
    corners, the worst place), compare the total albedo with the true lobes there.
    mode 'alpha' / 'eta' / 'base' interpolates only that axis, 'all' all three.
    alpha nodes on [0.01, 1]: 'log' (uniform in log alpha) or 'sqrt' (uniform in sqrt alpha);
    eta nodes on [1.05, 3]: 'log_eta_m1' (uniform in log(eta - 1)) or 'f0' (uniform in f0)."""
    grid = Grid(nmu, mapping)
    AN = np.geomspace(0.01, 1, n_alpha) if alpha_nodes == 'log' else np.linspace(0.1, 1, n_alpha) ** 2
    if eta_nodes == 'f0':
        f0 = np.linspace(((1.05 - 1) / 2.05) ** 2, 0.25, n_eta)
        EN = (1 + np.sqrt(f0)) / (1 - np.sqrt(f0))
        emid = lambda a, b: (lambda f: (1 + np.sqrt(f)) / (1 - np.sqrt(f)))(
            0.5 * (((a - 1) / (a + 1)) ** 2 + ((b - 1) / (b + 1)) ** 2))
    else:
        EN = 1 + np.exp(np.linspace(np.log(0.05), np.log(2.0), n_eta))
        emid = lambda a, b: 1 + np.sqrt((a - 1) * (b - 1))
    amid = (lambda a, b: np.sqrt(a * b)) if alpha_nodes == 'log' else (lambda a, b: (0.5 * (np.sqrt(a) + np.sqrt(b))) ** 2)
    bcache = {}
    def bd(ndf, a):
        if (ndf, a) not in bcache:
            bcache[(ndf, a)] = BaseData(Lobe(ndf, a), grid, MU_TEST)
        return bcache[(ndf, a)]
    ca = sorted(set([0, n_alpha // 8, n_alpha // 4, n_alpha // 2, n_alpha - 2]))
    ce = [0, n_eta // 4, n_eta // 2, n_eta - 2]
    print('\n== multi-D tables: alpha nodes %s x %d on [0.01, 1], eta nodes %s x %d on [1.05, 3], '
          'mu nodes %d (%s); queried mid-cell ==' % (alpha_nodes, n_alpha, eta_nodes, n_eta, nmu, mapping))
    for mode in modes:
        worst = {}
        for it in ca:
            for je in ce:
                for ndf, ib in (('ggx', 0), ('ggx', n_alpha // 2), ('beckmann', n_alpha // 8),
                                ('ggx', n_alpha - 2), ('lambert', None)):
                    ia = mode in ('alpha', 'all'); ie = mode in ('eta', 'all'); ibb = mode in ('base', 'all')
                    at_c = [AN[it], AN[it + 1]] if ia else [amid(AN[it], AN[it + 1])] * 2
                    et_c = [EN[je], EN[je + 1]] if ie else [emid(EN[je], EN[je + 1])] * 2
                    at = amid(*at_c) if ia else at_c[0]
                    eta = emid(*et_c) if ie else et_c[0]
                    top_true = TopData(Lobe('ggx', at, ('dielectric', eta)), grid, MU_TEST)
                    tops = [TopData(Lobe('ggx', at_c[a], ('dielectric', et_c[b])), grid, MU_TEST)
                            for a in (0, 1) for b in (0, 1)]
                    if ndf == 'lambert':
                        bt = BaseData(Lobe('lambert'), grid, MU_TEST)
                        E_i = sum(0.25 * tp.E_nodes for tp in tops)           # E_top table, bilinear
                        lm, lw = lambert_points()
                        gn = (1 - E_i) / np.sqrt(1 - np.sum(lw * grid.interp(E_i, lm)))
                    else:
                        ab_c = [AN[ib], AN[ib + 1]] if ibb else [amid(AN[ib], AN[ib + 1])] * 2
                        bt = bd(ndf, amid(*ab_c) if ibb else ab_c[0])
                        gn = sum(0.125 * Pair(tp, bd(ndf, ab)).g_nodes for tp in tops for ab in ab_c)
                    S = grid.interp(gn, bt.mi_t) * grid.interp(gn, MU_TEST[:, None])
                    tot = top_true.E_true_test + np.sum(bt.w_t * S, 1)
                    ref = top_true.E_true_test + (1 - top_true.E_true_test) * bt.A_test
                    norm = top_true.E_true_test + (tot - top_true.E_true_test) / bt.A_test
                    r = np.array([np.max(tot - 1), np.max(norm - 1), np.max(np.abs(tot - ref))])
                    k = 'lambert' if ndf == 'lambert' else 'microfacet'
                    worst[k] = np.maximum(worst.get(k, -9), r)
        for k, v in worst.items():
            print('   interpolate %-5s  base %-10s  gain %9.2e  ngain %9.2e  |total - one-sided| %9.2e'
                  % (mode, k, *v))


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--nmu', type=int, default=65, help='mu nodes of the tables')
    ap.add_argument('--map', default='log', choices=['log', 'sqrt'], help='mu node mapping')
    ap.add_argument('--check', action='store_true', help='quadrature checks only')
    ap.add_argument('--extra', action='store_true', help='also base-Fresnel and other-top checks')
    ap.add_argument('--params', action='store_true', help='only the multi-D (alpha, eta) table check')
    ap.add_argument('--n-alpha', type=int, default=64)
    ap.add_argument('--n-eta', type=int, default=32)
    ap.add_argument('--alpha-nodes', default='log', choices=['log', 'sqrt'])
    ap.add_argument('--eta-nodes', default='log_eta_m1', choices=['log_eta_m1', 'f0'])
    args = ap.parse_args()
    np.seterr(all='ignore')
    if args.params:
        param_interp_check(args.nmu, args.map, args.n_alpha, args.n_eta, args.alpha_nodes, args.eta_nodes)
        sys.exit(0)
    quadrature_checks()
    if args.check:
        sys.exit(0)
    reciprocity_check(Grid(args.nmu, args.map))
    run(args.nmu, args.map)
    if args.extra:
        fresnel_base_check(args.nmu, args.map)
        other_tops_check(args.nmu, args.map)
