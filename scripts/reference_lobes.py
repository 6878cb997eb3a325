"""reference_lobes.py -- multi-lobe materials (SPEC 10) for the independent Python oracle.

reference_values.py reads a material and evaluates one lobe from SPEC 1-3; this
module adds what SPEC 10 builds on top: `lobe NAME { ... }` blocks combined by
`bsdf = EXPR;` (NAME, W * X, X + Y, mix(X, Y, T), layer(TOP, BASE [, weight = W])),
and Kulla-Conty's energy term, which a layer needs for its car-paint base.

It is written from SPEC 10 and docs/design-notes/layer-albedo-scaling.md (the
chosen layer formula and what its bake tabulates), never from the C++ sources
nor from scripts/layer_proto.py, so that it is a second reading of the same
text. Where the C++ (and the prototype) bake tables of 65 log-mu nodes and
interpolate them linearly, this module is meant to be the "exact" layer:

- directional albedos E(mu) by its own quadrature over the half vector: panels
  in theta_h graded geometrically around the lobe's width, breaks where the
  azimuth range starts to shrink and where it ends (with a square substitution
  that removes their square-root edges), the trapezoid rule over the azimuth
  where it is a whole period (exponentially convergent) and Gauss-Legendre
  where it is cut; every point evaluated by the oracle's one-lobe brdf();
- tables over mu on nodes uniform in x with mu = sinh(5x)/sinh(5), read by cubic
  Lagrange interpolation in x (not linear), averages by Simpson's rule;
- the layer's g solves the balance g(mu_o) Int g(mu_i) f_base mu_i dw_i =
  u(mu_o) A_b(mu_o) by collocation at 129 nodes, g inside the integral cubic
  in x (so the residual between nodes is ~1e-7, well below the 3e-4 of the
  C++ tables), with the closed form u / sqrt(1 - Ebar) for a Lambertian base.

Measured: doubling every quadrature rule changes E by <= 6e-7 (alpha 1 at
mu = 1e-5), <= 3e-8 from mu = 0.01 up; 65 instead of 129 nodes changes layered
values (coats alpha 0.03 and 0.3 over Lambert, conductor and GGX bases, normal
to grazing directions) by <= 7e-7; the white furnace of a coat over white
Lambert is 1 within 4e-8.

Everything is pure Python (math only): a few seconds per layer bake (a table of
E_top and the base's transport at 129 nodes), cached per parameter set for the
run. Its checks (`reference_values.py --selftest`) are in reference_lobes_selftest.py.
"""

import math

import reference_values as rv

PI = math.pi
MU_NODES = 129            # nodes of every table over mu
MU_MAP_C = 5.0            # mu = sinh(C x)/sinh(C): spacing 5e-4 at mu = 0, 0.04 at mu = 1
MU_FLOOR = 1e-5           # node 0 (mu = 0) is evaluated at this mu: the albedo quadrature degenerates at 0
THETA_GL, PHI_GL, PHI_TRAPEZOID = 10, 20, 24   # points per theta panel, per cut and whole azimuth range
MU_GL = 4                 # Gauss-Legendre points per node interval for integrals over mu


def _gl01(n):
    nodes, weights = rv._legendre_nodes(n)
    return [((x + 1) / 2, w / 2) for x, w in zip(nodes, weights)]


_GL_THETA, _GL_PHI, _GL_MU = _gl01(THETA_GL), _gl01(PHI_GL), _gl01(MU_GL)

# ---------------------------------------------------------------------------
# Tables over mu: nodes, cubic interpolation, integrals
# ---------------------------------------------------------------------------

_SINH_C = math.sinh(MU_MAP_C)


def mu_of_x(x):
    return math.sinh(MU_MAP_C * x) / _SINH_C


def x_of_mu(mu):
    return math.asinh(mu * _SINH_C) / MU_MAP_C


# Tables cached per lobe (or per top and base) for the run: E(mu) at the nodes,
# the Kulla-Conty terms, the layer bakes.
_albedo_tables, _ms_factors, _layer_bakes = {}, {}, {}


def use_nodes(n):
    """Sets the node count of every table (the selftest compares two counts); clears the caches."""
    global MU_NODES, NODE_MU, NODE_MU_EVAL, MU_QUADRATURE
    MU_NODES = n
    NODE_MU = [mu_of_x(k / (n - 1)) for k in range(n)]
    NODE_MU_EVAL = [max(mu, MU_FLOOR) for mu in NODE_MU]
    MU_QUADRATURE = _mu_quadrature()
    for cache in (_albedo_tables, _ms_factors, _layer_bakes):
        cache.clear()


def stencil(mu):
    """Cubic Lagrange weights of the four nodes around mu: [(node, weight)]."""
    t = x_of_mu(min(max(mu, 0.0), 1.0)) * (MU_NODES - 1)
    j = min(max(int(t) - 1, 0), MU_NODES - 4)
    t -= j
    return [(j, -(t - 1) * (t - 2) * (t - 3) / 6), (j + 1, t * (t - 2) * (t - 3) / 2),
            (j + 2, -t * (t - 1) * (t - 3) / 2), (j + 3, t * (t - 1) * (t - 2) / 6)]


def interpolate(table, mu):
    """table: per-node rgb tuples; the rgb value at mu."""
    out = [0.0, 0.0, 0.0]
    for k, w in stencil(mu):
        for c in range(3):
            out[c] += w * table[k][c]
    return tuple(out)


def _mu_quadrature():
    """(mu, weight) with sum w q(mu) ~ Int_0^1 q(mu) dmu: Gauss-Legendre per node interval in x."""
    h = 1.0 / (MU_NODES - 1)
    out = []
    for k in range(MU_NODES - 1):
        for s, w in _GL_MU:
            x = (k + s) * h
            out.append((mu_of_x(x), w * h * MU_MAP_C * math.cosh(MU_MAP_C * x) / _SINH_C))
    return out


use_nodes(MU_NODES)


def cosine_average(table):
    """2 Int_0^1 E(mu) mu dmu of a node table, by Simpson's rule in x (the integrand is smooth in x)."""
    h = 1.0 / (MU_NODES - 1)
    out = [0.0, 0.0, 0.0]
    for k in range(MU_NODES):
        x = k * h
        w = (1 if k in (0, MU_NODES - 1) else 4 if k % 2 else 2) * h / 3
        jac = MU_MAP_C * math.cosh(MU_MAP_C * x) / _SINH_C
        for c in range(3):
            out[c] += 2 * w * table[k][c] * NODE_MU[k] * jac
    return tuple(out)


# ---------------------------------------------------------------------------
# One lobe: its value and the quadrature of its directional albedo
# ---------------------------------------------------------------------------


def _freeze(v):
    if isinstance(v, dict):
        return tuple(sorted((k, _freeze(x)) for k, x in v.items()))
    return v


class ResolvedLobe:
    """One lobe's models and parameters for one evaluation; hashable, so tables cache on it."""

    def __init__(self, models, params):
        self.models, self.params = models, params
        self.key = (_freeze(models), _freeze(params))

    def __eq__(self, other):
        return isinstance(other, ResolvedLobe) and self.key == other.key

    def __hash__(self):
        return hash(self.key)

    def with_models(self, **changes):
        return ResolvedLobe({**self.models, **changes}, self.params)

    def albedo_rgb(self):
        return self.params["diffuse"]["albedo"] if self.models["diffuse"] == "lambert" else (0.0, 0.0, 0.0)


def _unit_pair(wi, wo):
    """SPEC 2's direction rules, as brdf() applies them; None where f = 0."""
    for name, w in (("wi", wi), ("wo", wo)):
        if not abs(math.sqrt(rv.dot(w, w)) - 1) <= 1e-3:
            raise ValueError("%s = %s is not a unit vector within 1e-3" % (name, w))
    wi, wo = rv.normalize(wi), rv.normalize(wo)
    return None if wi[2] <= 0 or wo[2] <= 0 else (wi, wo)


def lobe_value(lobe, wi, wo):
    """f of one lobe: the one-lobe brdf() (SPEC 2), plus f_ms with energy = kulla_conty."""
    if lobe.models["ndf"] is None:  # SPEC 10: a lobe with only diffuse = lambert(..)
        if _unit_pair(wi, wo) is None:
            return (0.0, 0.0, 0.0)
        return tuple(a / PI for a in lobe.albedo_rgb())
    f = rv.brdf(lobe.models, lobe.params, wi, wo)
    if lobe.models["energy"] == "kulla_conty":
        pair = _unit_pair(wi, wo)
        if pair is not None:
            ms = kulla_conty_ms(lobe, pair[0][2], pair[1][2])
            f = tuple(a + b for a, b in zip(f, ms))
    return f


def _theta_scale(lobe):
    """The polar width of the lobe's microfacet normals, where the theta panels start doubling."""
    ndf, p = lobe.models["ndf"], lobe.params["ndf"]
    if p.get("alpha_x", 1) != p.get("alpha_y", 1):
        raise ValueError("the oracle's albedo quadrature is for isotropic lobes only")
    if ndf == "blinn_phong":
        return math.sqrt(2 / (p["exponent"] + 2))
    return min(p.get("alpha_x", p.get("alpha", 0.05)), 1.0)


def _theta_points(a, b, cluster_a, cluster_b):
    """Gauss-Legendre (theta, weight) on [a, b]; a square substitution at an end with a sqrt edge."""
    out = []
    for s, w in _GL_THETA:
        if cluster_a and cluster_b:
            t, d = a + (b - a) * s * s * (3 - 2 * s), 6 * (b - a) * s * (1 - s)
        elif cluster_a:
            t, d = a + (b - a) * s * s, 2 * (b - a) * s
        elif cluster_b:
            t, d = b - (b - a) * (1 - s) ** 2, 2 * (b - a) * (1 - s)
        else:
            t, d = a + (b - a) * s, b - a
        out.append((t, w * d))
    return out


def _specular_evaluator(spec):
    """f(wi, wo, h, wo.h) of a specular lobe for the quadrature, by the oracle's own D, G and F.

    The same formula as brdf() (SPEC 2) without its per-call checks and
    renormalization (the quadrature's directions are unit by construction), and
    with one Fresnel evaluation when the channels are equal: brdf() itself
    costs 2/3 of a bake. The selftest compares the two.
    """
    models, p = spec.models, spec.params
    ndf, masking, fresnel = models["ndf"], models["masking"], models["fresnel"]
    if ndf == "ward":
        return lambda wi, wo, h, oh: rv.brdf(models, p, wi, wo)
    pn, pf = p["ndf"], p["fresnel"]
    pm = {**pn, **p["masking"]}
    gray = all(v[0] == v[1] == v[2] for v in pf.values())

    def evaluate_at(wi, wo, h, oh):
        spec_value = rv.ndf_D(ndf, pn, h) * rv.masking_G(masking, ndf, pm, wi, wo, h) / (4 * wi[2] * wo[2])
        c = min(1.0, oh)  # wi.h = wo.h for the half vector
        if gray:
            f = rv.fresnel_F(fresnel, pf, c, 0) * spec_value
            return (f, f, f)
        return tuple(rv.fresnel_F(fresnel, pf, c, ch) * spec_value for ch in range(3))

    return evaluate_at


def specular_points(lobe, mu_o):
    """[(mu_i, rgb weight)] with sum w q(mu_i) ~ Int q(mu_i) f_spec(wi, wo) mu_i dwi, for n.wo = mu_o.

    Over the half vector h = (theta, phi): dwi = 4 (wo.h) dwh. wi is above the
    horizon for every phi while theta < pi/4 - theta_o/2, for none beyond
    pi/4 + theta_o/2, and in between for |phi| < phi_max(theta).
    """
    spec = lobe.with_models(diffuse="none", energy="none")
    so = math.sqrt(max(0.0, 1 - mu_o * mu_o))
    wo = (so, 0.0, mu_o)
    theta_o = math.atan2(so, mu_o)
    theta_a, theta_b = PI / 4 - theta_o / 2, PI / 4 + theta_o / 2
    breaks = {0.0, theta_b}
    if theta_a > 0:
        breaks.add(theta_a)
    step = _theta_scale(spec) / 16
    while step < theta_b:
        breaks.add(step)
        step *= 2
    breaks = sorted(breaks)
    evaluate_at = _specular_evaluator(spec)
    out = []
    for a, b in zip(breaks, breaks[1:]):
        if b - a < 1e-12 * theta_b:
            continue
        for theta, wt in _theta_points(a, b, a == theta_a and so > 0, b == theta_b and so > 0):
            st, ct = math.sin(theta), math.cos(theta)
            if so == 0 or theta <= theta_a:
                # A whole period of a smooth even function of phi: the trapezoid rule on [0, pi].
                m = PHI_TRAPEZOID
                phis = [(k * PI / m, (0.5 if k in (0, m) else 1.0) * PI / m) for k in range(m + 1)]
            else:
                phi_max = math.acos(min(1.0, max(-1.0, -mu_o * math.cos(2 * theta) / (so * math.sin(2 * theta)))))
                phis = [(phi_max * s, phi_max * w) for s, w in _GL_PHI]
            for phi, wp in phis:
                h = (st * math.cos(phi), st * math.sin(phi), ct)
                oh = so * h[0] + mu_o * ct
                wi = (2 * oh * h[0] - so, 2 * oh * h[1], 2 * oh * ct - mu_o)
                if wi[2] <= 0:
                    continue
                f = evaluate_at(wi, wo, h, oh)
                jac = 2 * wi[2] * 4 * oh * st * wt * wp  # 2: phi and -phi
                out.append((wi[2], (f[0] * jac, f[1] * jac, f[2] * jac)))
    return out


def specular_albedo_table(lobe):
    """E(mu) of the lobe's microfacet term at every node (its own Fresnel, per channel)."""
    if lobe not in _albedo_tables:
        table = []
        for mu in NODE_MU_EVAL:
            s = [0.0, 0.0, 0.0]
            for _, w in specular_points(lobe, mu):
                for c in range(3):
                    s[c] += w[c]
            table.append(tuple(s))
        _albedo_tables[lobe] = table
    return _albedo_tables[lobe]


def _kulla_conty_terms(lobe):
    """(E table with F = 1, E_avg, rgb factor F_avg^2 E_avg / ((1 - E_avg)(1 - F_avg (1 - E_avg)))) (SPEC 3)."""
    if lobe not in _ms_factors:
        white = lobe.with_models(fresnel="none", diffuse="none", energy="none")
        table = specular_albedo_table(white)
        e_avg = cosine_average(table)[0]
        factor = []
        for c in range(3):
            f_avg = 2 * rv.integrate(lambda mu: rv.fresnel_F(lobe.models["fresnel"], lobe.params["fresnel"], mu, c) * mu,
                                     0.0, 1.0, 1e-12)
            factor.append(f_avg * f_avg * e_avg / ((1 - e_avg) * (1 - f_avg * (1 - e_avg))))
        _ms_factors[lobe] = (table, e_avg, tuple(factor))
    return _ms_factors[lobe]


def kulla_conty_ms(lobe, mu_i, mu_o):
    table, _, factor = _kulla_conty_terms(lobe)
    ei, eo = interpolate(table, mu_i)[0], interpolate(table, mu_o)[0]
    return tuple((1 - ei) * (1 - eo) / PI * k for k in factor)


def lobe_points(lobe, mu_o):
    """The measure f(wi, wo) mu_i dwi of the whole lobe over mu_i, as [(mu_i, rgb weight)]."""
    out = specular_points(lobe, mu_o) if lobe.models["ndf"] is not None else []
    rho = lobe.albedo_rgb()
    ms = lobe.models["energy"] == "kulla_conty"
    if any(rho) or ms:
        for mu, w in MU_QUADRATURE:
            f = [r / PI for r in rho]
            if ms:
                f = [a + b for a, b in zip(f, kulla_conty_ms(lobe, mu, mu_o))]
            out.append((mu, tuple(2 * PI * mu * w * x for x in f)))
    return out


# ---------------------------------------------------------------------------
# The bsdf expression: a tree of lobes, its value, its albedo measure, the layer
# ---------------------------------------------------------------------------
# Resolved trees: ("lobe", ResolvedLobe) ("scale", w, X) ("sum", X, Y) ("mix", X, Y, t)
# ("layer", TOP, BASE, w or None); w and t are rgb tuples, already clamped.


def _rgb(v):
    return v if isinstance(v, tuple) else (v, v, v)


def resolve_bsdf(mat, e, env, params_of):
    """The bsdf expression e of material mat, with values from env, as a resolved tree."""

    def is_bsdf(x):
        if x[0] == "name":
            return x[1] in mat.lobes
        if x[0] in ("+", "*"):
            return is_bsdf(x[1]) or is_bsdf(x[2])
        return x[0] == "call" and (x[1] == "layer" or (x[1] == "mix" and any(is_bsdf(a) for a in x[2])))

    def value(x, lo, hi):
        return tuple(min(max(c, lo), hi) for c in _rgb(rv.evaluate(x, env)))

    def walk(x):
        if x[0] == "name" and x[1] in mat.lobes:
            return ("lobe", params_of(x[1]))
        if x[0] == "+" and is_bsdf(x[1]) and is_bsdf(x[2]):
            return ("sum", walk(x[1]), walk(x[2]))
        if x[0] == "*" and is_bsdf(x[1]) != is_bsdf(x[2]):
            # SPEC 10 writes W * X; X * W means the same, so it is read too.
            w, lobes = (x[1], x[2]) if is_bsdf(x[2]) else (x[2], x[1])
            return ("scale", value(w, 0.0, math.inf), walk(lobes))
        if x[0] == "call" and x[1] == "mix" and len(x[2]) == 3:
            return ("mix", walk(x[2][0]), walk(x[2][1]), value(x[2][2], 0.0, 1.0))
        if x[0] == "call" and x[1] == "layer" and len(x[2]) in (2, 3):
            names = x[3] if len(x) > 3 else [None] * len(x[2])
            if names[0] is not None or names[1] is not None or (len(names) == 3 and names[2] not in (None, "weight")):
                raise ValueError("layer(TOP, BASE [, weight = W]) takes two lobes and an optional weight")
            # The weight of a coat is a fraction, as W in OpenPBR's coat mix; SPEC 10 says no range: clamped to [0, 1].
            w = value(x[2][2], 0.0, 1.0) if len(x[2]) == 3 else None
            return ("layer", walk(x[2][0]), walk(x[2][1]), w)
        raise ValueError("not a combination of lobes: %r" % (x,))

    return walk(e)


def tree_of(mat, values):
    """The resolved bsdf tree of a material with lobes, for the given input values."""
    env = mat.environment(values)
    return resolve_bsdf(mat, mat.bsdf, env,
                        lambda name: ResolvedLobe(mat.lobes[name][0], rv.resolve_models(*mat.lobes[name], env)))


def eval_material(mat, wi, wo, values):
    return value_of(tree_of(mat, values), wi, wo)


def value_of(tree, wi, wo):
    kind = tree[0]
    if kind == "lobe":
        return lobe_value(tree[1], wi, wo)
    if kind == "scale":
        return tuple(w * f for w, f in zip(tree[1], value_of(tree[2], wi, wo)))
    if kind == "sum":
        return tuple(a + b for a, b in zip(value_of(tree[1], wi, wo), value_of(tree[2], wi, wo)))
    if kind == "mix":
        a, b, t = value_of(tree[1], wi, wo), value_of(tree[2], wi, wo), tree[3]
        return tuple((1 - t[c]) * a[c] + t[c] * b[c] for c in range(3))
    top, base = value_of(tree[1], wi, wo), value_of(tree[2], wi, wo)
    pair = _unit_pair(wi, wo)
    if pair is None:
        return (0.0, 0.0, 0.0)
    s = layer_scale(tree, pair[0][2], pair[1][2])
    w = tree[3] or (1.0, 1.0, 1.0)
    return tuple(w[c] * top[c] + (1 - w[c] + w[c] * s[c]) * base[c] for c in range(3))


def points_of(tree, mu_o):
    """The measure f(wi, wo) mu_i dwi of a tree over mu_i: [(mu_i, rgb weight)]."""
    kind = tree[0]
    if kind == "lobe":
        return lobe_points(tree[1], mu_o)
    if kind == "scale":
        return [(mu, tuple(a * b for a, b in zip(w, tree[1]))) for mu, w in points_of(tree[2], mu_o)]
    if kind == "sum":
        return points_of(tree[1], mu_o) + points_of(tree[2], mu_o)
    if kind == "mix":
        t = tree[3]
        return ([(mu, tuple((1 - t[c]) * w[c] for c in range(3))) for mu, w in points_of(tree[1], mu_o)]
                + [(mu, tuple(t[c] * w[c] for c in range(3))) for mu, w in points_of(tree[2], mu_o)])
    wgt = tree[3] or (1.0, 1.0, 1.0)
    out = [(mu, tuple(wgt[c] * w[c] for c in range(3))) for mu, w in points_of(tree[1], mu_o)]
    for mu, w in points_of(tree[2], mu_o):
        s = layer_scale(tree, mu, mu_o)
        out.append((mu, tuple((1 - wgt[c] + wgt[c] * s[c]) * w[c] for c in range(3))))
    return out


def albedo_of(tree, mu_o):
    """Directional albedo Int f(wi, wo) mu_i dwi of a tree, rgb."""
    s = [0.0, 0.0, 0.0]
    for _, w in points_of(tree, mu_o):
        for c in range(3):
            s[c] += w[c]
    return tuple(s)


def _albedo_table(tree):
    if tree[0] == "lobe" and tree[1].models["energy"] != "kulla_conty" and tree[1].models["ndf"] is not None:
        return [tuple(a + b for a, b in zip(e, tree[1].albedo_rgb())) for e in specular_albedo_table(tree[1])]
    return [albedo_of(tree, mu) for mu in NODE_MU_EVAL]


def white_base(tree):
    """The base as the layer's bake sees it: Fresnel 1 in its lobes (design note 5; f_ms kept, its F_avg 1).

    A nested layer's top keeps its Fresnel: it is that layer's coat, whose
    transmission is what the nested layer is about (a reading of the note,
    which names nested layers as bases without saying more).
    """
    kind = tree[0]
    if kind == "lobe":
        return ("lobe", tree[1].with_models(fresnel="none"))
    if kind == "layer":
        return ("layer", tree[1], white_base(tree[2]), tree[3])
    return (kind,) + tuple(white_base(x) if isinstance(x, tuple) and isinstance(x[0], str) else x for x in tree[1:])


def is_diffuse(tree):
    if tree[0] == "lobe":
        return tree[1].models["ndf"] is None
    return tree[0] != "layer" and all(is_diffuse(x) for x in tree[1:] if isinstance(x, tuple) and isinstance(x[0], str))


def layer_bake(top, base):
    """(how, data) of layer(top, base): ("lambert", (E table, Ebar)) or ("g", g node table); cached."""
    key = (top, base)
    if key in _layer_bakes:
        return _layer_bakes[key]
    e_top = _albedo_table(top)
    u = [tuple(max(0.0, 1 - e) for e in row) for row in e_top]
    if is_diffuse(base):
        result = ("lambert", (e_top, cosine_average(e_top)))
    else:
        result = ("g", solve_balance(u, white_base(base))[0])
    _layer_bakes[key] = result
    return result


def base_transport(base):
    """M[c][j][k] = Int basis_k(mu_i) f_base(wi, wo_j) mu_i dwi, and the base albedo A[c][j] at the nodes."""
    m = [[[0.0] * MU_NODES for _ in range(MU_NODES)] for _ in range(3)]
    a = [[0.0] * MU_NODES for _ in range(3)]
    for j, mu_o in enumerate(NODE_MU_EVAL):
        points = points_of(base, mu_o)
        gray = all(w[0] == w[1] == w[2] for _, w in points)
        for c in ((0,) if gray else (0, 1, 2)):
            row = m[c][j]
            for mu_i, w in points:
                for k, b in stencil(mu_i):
                    row[k] += b * w[c]
            a[c][j] = math.fsum(w[c] for _, w in points)
        if gray:  # a white base (the usual case: its Fresnel is 1 here) is one channel
            for c in (1, 2):
                m[c][j], a[c][j] = list(m[0][j]), a[0][j]
    return m, a


def solve_balance(u, base):
    """g at the nodes, per channel, with g_j (M g)_j = u_j A_j; and the worst relative residual."""
    m, a = base_transport(base)
    g_rows = [[0.0] * 3 for _ in range(MU_NODES)]
    worst = 0.0
    solved = {}
    for c in range(3):
        b = [u[j][c] * a[c][j] for j in range(MU_NODES)]
        key = (tuple(b), tuple(map(tuple, m[c])))
        if key not in solved:
            solved[key] = _balance_channel(m[c], b)
        g, res = solved[key]
        worst = max(worst, res)
        for j in range(MU_NODES):
            g_rows[j][c] = g[j]
    return [tuple(r) for r in g_rows], worst


def _balance_channel(m, b):
    """The symmetric fixed point g <- sqrt(g b / (M g)): at a solution g (M g) = b, and the
    geometric mean of the old g and b / (M g) halves the log-error of a symmetric kernel per step."""
    n = len(b)
    mv = lambda g: [sum(row[k] * g[k] for k in range(n)) for row in m]
    ones = mv([1.0] * n)
    g = [math.sqrt(b[j] / ones[j]) if b[j] > 0 else 0.0 for j in range(n)]
    for _ in range(5000):
        mg = mv(g)
        new = [math.sqrt(g[j] * b[j] / mg[j]) if b[j] > 0 and mg[j] > 0 else 0.0 for j in range(n)]
        change = max((abs(x - y) / y for x, y in zip(new, g) if y > 0), default=0.0)
        g = new
        if change < 1e-14:
            break
    mg = mv(g)
    res = max((abs(g[j] * mg[j] - b[j]) / b[j] for j in range(n) if b[j] > 0), default=0.0)
    return g, res


def layer_scale(tree, mu_i, mu_o):
    """S = g(mu_i) g(mu_o) of layer(TOP, BASE), per channel."""
    how, data = layer_bake(tree[1], tree[2])
    if how == "lambert":
        table, e_bar = data
        ui, uo = interpolate(table, mu_i), interpolate(table, mu_o)
        return tuple(max(0.0, 1 - ui[c]) * max(0.0, 1 - uo[c]) / (1 - e_bar[c]) for c in range(3))
    gi, go = interpolate(data, mu_i), interpolate(data, mu_o)
    return tuple(max(0.0, gi[c]) * max(0.0, go[c]) for c in range(3))
