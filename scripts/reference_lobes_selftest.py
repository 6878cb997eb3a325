"""reference_lobes_selftest.py -- checks of reference_lobes.py (run by reference_values.py --selftest).

Against facts that do not depend on the code under test: brdf() for the
quadrature's shortcut evaluator, the design note's two published E(mu = 1)
values (another quadrature), a plain quadrature over wi, the white furnace
(Kulla-Conty with F = 1; a dielectric coat over a white Lambert lobe; over a
white microfacet base of albedo 1), the closed form of g for a Lambertian base,
the balance residual at and between the nodes, and reciprocity.
"""

import math

import reference_lobes as lobes
import reference_values as rv
from reference_lobes import PI, albedo_of, layer_bake, solve_balance, tree_of

_SELFTEST_MATERIALS = """
material coat_over {
    input alpha = 0.3;
    input base_alpha = 0.16;
    lobe coat { ndf = ggx(alpha); masking = smith_height_correlated; fresnel = dielectric(1.5); }
    lobe white { diffuse = lambert(1); }
    lobe metal { ndf = ggx(base_alpha); masking = smith_height_correlated;
                 fresnel = conductor(eta = rgb(0.2, 0.92, 1.1), k = rgb(3.9, 2.45, 2.14)); energy = kulla_conty; }
    lobe white_metal { ndf = ggx(base_alpha); masking = smith_height_correlated; energy = kulla_conty; }
    bsdf = layer(coat, white) + layer(coat, metal, weight = 0.25) + layer(coat, 0.5 * white + 0.5 * metal)
         + layer(coat, white_metal);
}
"""


def _unit(theta, phi):
    return (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))


def selftest(check):
    """Checks of the albedo quadrature and of the layer against facts that do not depend on it."""
    mats = {m.name: m for m in (rv.Material(n, st) for n, st in rv.Parser(rv.tokenize(_SELFTEST_MATERIALS)).program())}
    mat = mats["coat_over"]

    def part(values, k):  # the k-th of the four layers of coat_over's bsdf sum
        tree = tree_of(mat, values)
        parts = []
        while tree[0] == "sum":
            parts.insert(0, tree[2])
            tree = tree[1]
        return ([tree] + parts)[k]

    white_f1 = ("lobe", part({}, 3)[2][1])  # GGX, F = 1, Kulla-Conty
    white_f1_no_ms = ("lobe", white_f1[1].with_models(energy="none"))
    # The quadrature's shortcut evaluator is brdf().
    for lobe in (part({}, 0)[1][1], part({}, 1)[2][1]):
        for wi, wo in (((0.6, 0, 0.8), (-0.36, 0.48, 0.8)), (rv.normalize((0.28, -0.959, 0.05)), (0, 0.6, 0.8))):
            h = rv.normalize(tuple(a + b for a, b in zip(wi, wo)))
            spec = lobe.with_models(diffuse="none", energy="none")
            check("quadrature evaluator = brdf() (%s)" % lobe.models["fresnel"],
                  lobes._specular_evaluator(spec)(wi, wo, h, rv.dot(wo, h))[2], rv.brdf(spec.models, spec.params, wi, wo)[2], 1e-13)
    # E(mu = 1) of white GGX height-correlated lobes, as the design note's prototype (another quadrature) gives them.
    for alpha, want in ((0.5, 0.68785), (0.25, 0.91581)):
        lobe = ("lobe", white_f1_no_ms[1].__class__(white_f1_no_ms[1].models, {**white_f1_no_ms[1].params,
                "ndf": {"alpha": alpha, "alpha_x": alpha, "alpha_y": alpha}}))
        check("E(mu=1) white GGX alpha %g (design note, 5 digits)" % alpha, albedo_of(lobe, 1.0)[0], want, 1e-5)
    # The half-vector quadrature against a plain one over wi (theta_i, phi_i), at one wo.
    mu_o, lobe = 0.5, part({"alpha": 0.5}, 0)[1][1]
    wo = (math.sqrt(1 - mu_o * mu_o), 0.0, mu_o)
    plain = 2 * rv.integrate(lambda t: rv.integrate(
        lambda ph: rv.brdf(lobe.models, lobe.params, _unit(t, ph), wo)[0], 0, PI, 1e-9) * math.cos(t) * math.sin(t),
        0, PI / 2, 1e-9)
    check("half-vector quadrature = plain quadrature over wi", albedo_of(("lobe", lobe), mu_o)[0], plain, 1e-7)
    # Kulla-Conty with F = 1 restores the whole energy.
    for mu in (0.01, 0.3, 1.0):
        check("white furnace, GGX 0.16 + kulla_conty, mu_o %g" % mu, albedo_of(white_f1, mu)[0], 1.0, 1e-5)
    # White furnace of layer(dielectric top, white Lambert), several alpha and wo.
    for alpha in (0.03, 0.3, 1.0):
        tree = part({"alpha": alpha}, 0)
        for mu in (0.01, 0.1, 0.5, 1.0):
            check("white furnace, layer(ggx %g eta 1.5, white lambert), mu_o %g" % (alpha, mu), albedo_of(tree, mu)[0], 1.0, 1e-4)
    # The balance solved at the nodes for a Lambert base is the closed form.
    tree = part({"alpha": 0.03}, 0)
    table, e_bar = layer_bake(tree[1], tree[2])[1]
    g, residual = solve_balance([tuple(1 - e for e in row) for row in table], tree[2])
    check("balance over white lambert = u / sqrt(1 - Ebar)", max(
        abs(g[j][0] * math.sqrt(1 - e_bar[0]) / (1 - table[j][0]) - 1) for j in range(lobes.MU_NODES)) + 1, 1.0, 1e-7)
    # The balance residual: at the nodes (the solve) and between them (g interpolated), for a glossy base,
    # where the identity total = E_top + (1 - E_top) A_b holds for the base the bake saw (F = 1).
    tree = part({"alpha": 0.03}, 3)
    u = [tuple(1 - e for e in row) for row in lobes._albedo_table(tree[1])]
    check("balance residual at the nodes", solve_balance(u, white_f1)[1] + 1, 1.0, 1e-10)
    for mu in (0.013, 0.37, 0.81):
        e, a = albedo_of(tree[1], mu)[0], albedo_of(white_f1, mu)[0]
        check("balance between the nodes, mu_o %g" % mu, albedo_of(tree, mu)[0], e + (1 - e) * a, 1e-5)
    # A base of albedo 1 that is not Lambertian (F = 1 and Kulla-Conty) neither gains nor loses.
    for alpha, base_alpha in ((0.03, 0.03), (0.3, 1.0)):
        tree = part({"alpha": alpha, "base_alpha": base_alpha}, 3)
        for mu in (0.01, 0.2, 1.0):
            check("white furnace, layer(ggx %g, white ggx %g + kc), mu_o %g" % (alpha, base_alpha, mu),
                  albedo_of(tree, mu)[0], 1.0, 1e-4)
    # Reciprocity of the whole combination (three kinds of layer; rgb).
    for wi, wo in (((0.6, 0, 0.8), (-0.36, 0.48, 0.8)), ((0.9999499987, 0, 0.01), (0, 0.6, 0.8)),
                   ((0.28, -0.959, 0.05), (0.3, 0.4, math.sqrt(0.75)))):
        f, b = mat.eval(wi, wo, {}), mat.eval(wo, wi, {})
        for c in range(3):
            check("reciprocity f(wi, wo) = f(wo, wi), channel %d" % c, f[c], b[c], 1e-12)
