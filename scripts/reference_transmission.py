"""reference_transmission.py -- lobes that scatter below the surface (SPEC 11) for the Python oracle.

reference_values.py evaluates a lobe that reflects above the surface; this module
adds `scatter = transmit | both` and `thin = true` on a lobe with
`fresnel = dielectric(eta)`. It is written from SPEC 11 and the papers it cites,
never from the C++ sources, and in a different form from them: Walter et al.
2007's f_r and f_t with absolute indices (eta_i, eta_o the indices on wi's and
wo's side, the inside being -z with index eta), the transmission half vector
h_t = -(eta_i wi + eta_o wo), Fresnel at the outside direction's cosine, and
the height-correlated Smith masking of a transmitted pair as Heitz 2014's
Beta function B(1 + Lambda(wi), 1 + Lambda(wo)) by math.lgamma (for a
reflected pair on either side, 1 / (1 + Lambda(wi) + Lambda(wo))). Radiance
transport: f_t carries eta_o^2 / (eta_i wi.h + eta_o wo.h)^2.

The thin sheet (thin = true): the reflection lobe of the directions mirrored
above the surface, weighted by the sheet's reflectance 2F / (1 + F) for a pair
on one side and its transmittance (1 - F) / (1 + F) for a pair across it.
"""

import math

import reference_values as rv

ETA_CLAMP_FROM_ONE = 1e-3   # SPEC 11: eta within 1e-3 of 1 is moved away from 1


def whole_sphere(models):
    return models.get("scatter", "reflect") != "reflect" or models.get("thin", "false") == "true"


def _beta(a, b):
    if math.isinf(a) or math.isinf(b):
        return 0.0
    return math.exp(math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b))


def _mirror(w):
    return (w[0], w[1], abs(w[2]))


def _masking(models, pn, pm, wi, wo, h, transmitted):
    """G of the pair mirrored above the surface (wi, wo, h all with z >= 0)."""
    masking, ndf = models["masking"], models["ndf"]
    p = {**pn, **pm}
    if not transmitted:
        return rv.masking_G(masking, ndf, p, wi, wo, h)
    li, lo = rv.smith_lambda(ndf, p, wi), rv.smith_lambda(ndf, p, wo)
    # Across the surface the two directions see different sides of it: only
    # the heights correlate (the direction-correlated forms lose their azimuth term).
    if masking in ("smith_separable", "smith_direction_correlated"):
        return 1 / ((1 + li) * (1 + lo))
    if masking in ("smith_height_correlated", "smith_height_direction_correlated"):
        return _beta(1 + li, 1 + lo)
    raise ValueError("no transmission form for masking " + masking)


def _eta(params):
    eta = params["fresnel"]["eta"][0]
    if abs(eta - 1) < ETA_CLAMP_FROM_ONE:
        eta = 1 + ETA_CLAMP_FROM_ONE if eta >= 1 else 1 - ETA_CLAMP_FROM_ONE
    return eta


def bsdf(models, params, wi, wo, transport="radiance"):
    for name, w in (("wi", wi), ("wo", wo)):
        if not abs(math.sqrt(rv.dot(w, w)) - 1) <= 1e-3:
            raise ValueError("%s = %s is not a unit vector within 1e-3" % (name, w))
    wi, wo = rv.normalize(wi), rv.normalize(wo)
    if wi[2] == 0 or wo[2] == 0:
        return (0.0, 0.0, 0.0)
    scatter = models.get("scatter", "reflect")
    same_side = (wi[2] > 0) == (wo[2] > 0)
    if (same_side and scatter == "transmit") or (not same_side and scatter == "reflect"):
        return (0.0, 0.0, 0.0)
    pn, pm, pf = params["ndf"], params["masking"], params["fresnel"]
    if models.get("thin", "false") == "true":
        i, o = _mirror(wi), _mirror(wo)
        h = rv.normalize((i[0] + o[0], i[1] + o[1], i[2] + o[2]))
        lobe = rv.ndf_D(models["ndf"], pn, h) * _masking(models, pn, pm, i, o, h, False) / (4 * i[2] * o[2])
        out = []
        for ch in range(3):
            F = rv.fresnel_dielectric(min(1.0, rv.dot(o, h)), pf["eta"][ch])
            out.append((2 * F / (1 + F) if same_side else (1 - F) / (1 + F)) * lobe)
        return tuple(out)
    eta = _eta(params)
    n_i = 1.0 if wi[2] > 0 else eta
    n_o = 1.0 if wo[2] > 0 else eta
    if same_side:  # reflection outside or inside: the pair mirrored above, F from wo's side
        i, o = _mirror(wi), _mirror(wo)
        h = rv.normalize((i[0] + o[0], i[1] + o[1], i[2] + o[2]))
        F = rv.fresnel_dielectric(min(1.0, rv.dot(o, h)), eta if wo[2] > 0 else 1 / eta)
        v = F * rv.ndf_D(models["ndf"], pn, h) * _masking(models, pn, pm, i, o, h, False) / (4 * i[2] * o[2])
        return (v, v, v)
    ht = (-(n_i * wi[0] + n_o * wo[0]), -(n_i * wi[1] + n_o * wo[1]), -(n_i * wi[2] + n_o * wo[2]))
    length = math.sqrt(rv.dot(ht, ht))
    if length == 0:
        return (0.0, 0.0, 0.0)
    ht = tuple(x / length for x in ht)
    if ht[2] < 0:
        ht = (-ht[0], -ht[1], -ht[2])
    ih, oh = rv.dot(wi, ht), rv.dot(wo, ht)
    if ih * wi[2] <= 0 or oh * wo[2] <= 0:
        return (0.0, 0.0, 0.0)
    outside_cos = oh if wo[2] > 0 else ih
    F = rv.fresnel_dielectric(min(1.0, outside_cos), eta)
    G = _masking(models, pn, pm, _mirror(wi), _mirror(wo), ht, True)
    denom = n_i * ih + n_o * oh
    scale = n_o * n_o if transport == "radiance" else n_i * n_i
    v = abs(ih * oh / (wi[2] * wo[2])) * scale * (1 - F) * G * rv.ndf_D(models["ndf"], pn, ht) / (denom * denom)
    return (v, v, v)
