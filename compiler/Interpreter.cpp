// Interpreter: the reference formulas (SPEC section 3), one term at a time.
#include "Interpreter.h"

#include "Diagnostics.h"

#include <cmath>
#include <complex>

namespace facet {

namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

template <typename Real>
Real sq(Real x) { return x * x; }

template <typename Real>
bool finite(Real x) { using std::isfinite; return isfinite(x); }

// expm1(y)/y, continuous through y = 0 (where it is 1).
template <typename Real>
Real expm1OverX(Real y) {
    using std::expm1;
    if (y == 0) return 1;
    return expm1(y) / y;
}

// Composite 8-point Gauss-Legendre quadrature of f over [a, b].
template <typename Real, typename F>
Real integrate(const F& f, Real a, Real b, int panels) {
    static const long double nodes[4] = {0.1834346424956498049394761423601839807L,
                                         0.5255324099163289858177390491892463490L,
                                         0.7966664774136267395915539364758304368L,
                                         0.9602898564975362316835608685694729904L};
    static const long double weights[4] = {0.3626837833783619829651504492771956121L,
                                           0.3137066458778872873379622019866013132L,
                                           0.2223810344533744705443559944262408844L,
                                           0.1012285362903762591525313543099621901L};
    Real sum = 0, h = (b - a) / panels;
    for (int p = 0; p < panels; ++p) {
        Real mid = a + (p + Real(0.5)) * h, half = h / 2;
        for (int i = 0; i < 4; ++i) {
            Real d = half * Real(nodes[i]);
            sum += Real(weights[i]) * half * (f(mid - d) + f(mid + d));
        }
    }
    return sum;
}

// Beckmann Smith Lambda for a = cot(theta_v) / alpha_v (Walter et al. 2007):
// Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)), written with erfc so
// that it does not cancel for large a.
template <typename Real>
Real beckmannLambda(Real a) {
    using std::erfc; using std::exp; using std::sqrt;
    return (exp(-a * a) / (a * sqrt(kPi<Real>)) - erfc(a)) / 2;
}

}  // namespace

template <typename Real>
Real gaussianNdfNorm(Real alpha) {
    using std::cos; using std::exp; using std::min; using std::sin;
    // The integrand is negligible beyond 8 alpha (exp(-64)).
    Real upper = min(kPi<Real> / 2, 8 * alpha);
    auto f = [&](Real t) { return exp(-t * t / (alpha * alpha)) * cos(t) * sin(t); };
    return 2 * kPi<Real> * integrate<Real>(f, Real(0), upper, 64);
}

template <typename Real>
Real ResolvedMaterial<Real>::D(const Vec3<Real>& m) const {
    using std::atan2; using std::exp; using std::pow; using std::sqrt;
    if (m.z <= 0) return 0;
    const Real pi = kPi<Real>;
    Real x2 = m.x * m.x, y2 = m.y * m.y, z2 = m.z * m.z;
    switch (ndf) {
        case NdfModel::Ggx: {
            // 1 / (pi ax ay (mx^2/ax^2 + my^2/ay^2 + mz^2)^2)
            Real t = x2 / sq(alphaX) + y2 / sq(alphaY) + z2;
            return 1 / (pi * alphaX * alphaY * t * t);
        }
        case NdfModel::Beckmann: {
            // exp(-(mx^2/ax^2 + my^2/ay^2)/mz^2) / (pi ax ay mz^4)
            Real e = (x2 / sq(alphaX) + y2 / sq(alphaY)) / z2;
            return exp(-e) / (pi * alphaX * alphaY * z2 * z2);
        }
        case NdfModel::BlinnPhong:
            // (e + 2)/(2 pi) mz^e
            return (exponent + 2) / (2 * pi) * pow(m.z, exponent);
        case NdfModel::Gtr: {
            // c / (1 + (a^2 - 1) mz^2)^gamma with c = (g-1)(a^2-1) / (pi (1 - (a^2)^(1-g))),
            // rewritten as c = phi(L) / (pi phi((1-g) L)), L = ln a^2,
            // phi(y) = expm1(y)/y, which is exact at the limits g = 1 and a = 1.
            Real a2 = sq(alphaX);
            Real L = std::log(a2);
            Real c = expm1OverX(L) / (pi * expm1OverX((1 - gamma) * L));
            Real t = a2 * z2 + x2 + y2;  // = 1 + (a^2 - 1) mz^2 for a unit m
            return c / pow(t, gamma);
        }
        case NdfModel::Gaussian: {
            Real theta = atan2(sqrt(x2 + y2), m.z);
            return exp(-theta * theta / sq(alphaX)) / gaussianNorm;
        }
        case NdfModel::Ward: break;
    }
    internal_error << "D() called for ndf without a microfacet distribution";
}

template <typename Real>
Real ResolvedMaterial<Real>::lambda(const Vec3<Real>& v) const {
    using std::sqrt;
    Real ax = alphaX, ay = alphaY;
    if (ndf == NdfModel::BlinnPhong) ax = ay = sqrt(2 / (exponent + 2));
    // (vx^2 ax^2 + vy^2 ay^2) = alpha(v)^2 sin^2(theta_v)
    Real proj = sq(v.x * ax) + sq(v.y * ay);
    if (proj == 0) return 0;  // v = n: nothing is masked
    switch (ndf) {
        case NdfModel::Ggx: {
            // (-1 + sqrt(1 + x)) / 2 = x / (2 (1 + sqrt(1 + x))), x = alpha^2 tan^2
            Real x = proj / sq(v.z);
            return x / (2 * (1 + sqrt(1 + x)));
        }
        case NdfModel::Beckmann:
        case NdfModel::BlinnPhong: return beckmannLambda(v.z / sqrt(proj));
        default: break;
    }
    internal_error << "Smith Lambda requested for an NDF without a closed form";
}

template <typename Real>
Real ResolvedMaterial<Real>::smithG1(const Vec3<Real>& v, const Vec3<Real>& m) const {
    if (v.x * m.x + v.y * m.y + v.z * m.z <= 0) return 0;
    return 1 / (1 + lambda(v));
}

template <typename Real>
Real ResolvedMaterial<Real>::G(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h) const {
    using std::atan2; using std::max; using std::min; using std::abs;
    Real ci = wi.z, co = wo.z, nh = h.z;
    Real ih = wi.x * h.x + wi.y * h.y + wi.z * h.z;
    Real oh = wo.x * h.x + wo.y * h.y + wo.z * h.z;
    // lambda(phi) of Heitz 2014 / Ashikhmin et al., phi the azimuth between wi and wo.
    auto azimuthWeight = [&] {
        Real phi = atan2(abs(wi.x * wo.y - wi.y * wo.x), wi.x * wo.x + wi.y * wo.y);
        return Real(4.41) * phi / (Real(4.41) * phi + 1);
    };
    switch (masking) {
        case MaskingModel::None: return 1;
        case MaskingModel::Implicit: return ci * co;
        case MaskingModel::CookTorrance: return min(Real(1), min(2 * nh * co / oh, 2 * nh * ci / oh));
        case MaskingModel::Kelemen: return ci * co / (oh * oh);
        case MaskingModel::Neumann: return ci * co / max(ci, co);
        case MaskingModel::SchlickSmith: {
            auto g1 = [&](Real c) { return c / (c * (1 - schlickK) + schlickK); };
            return g1(ci) * g1(co);
        }
        case MaskingModel::SmithSeparable:
            if (ih <= 0 || oh <= 0) return 0;
            return 1 / ((1 + lambda(wi)) * (1 + lambda(wo)));
        case MaskingModel::SmithHeightCorrelated:
            if (ih <= 0 || oh <= 0) return 0;
            return 1 / (1 + lambda(wi) + lambda(wo));
        case MaskingModel::SmithDirectionCorrelated: {
            if (ih <= 0 || oh <= 0) return 0;
            Real g1i = 1 / (1 + lambda(wi)), g1o = 1 / (1 + lambda(wo));
            Real w = azimuthWeight();
            return w * g1i * g1o + (1 - w) * min(g1i, g1o);
        }
        case MaskingModel::SmithHeightDirectionCorrelated: {
            if (ih <= 0 || oh <= 0) return 0;
            Real li = lambda(wi), lo = lambda(wo);
            return 1 / (1 + max(li, lo) + azimuthWeight() * min(li, lo));
        }
    }
    internal_error << "unknown masking model";
}

template <typename Real>
Real ResolvedMaterial<Real>::F(Real c, int ch) const {
    using std::norm; using std::pow; using std::sqrt;
    switch (fresnel) {
        case FresnelModel::None: return 1;
        case FresnelModel::Schlick: {
            Real r0 = f0[ch];
            if (schlickFromEta) r0 = sq((eta[ch] - 1) / (eta[ch] + 1));
            return r0 + (1 - r0) * pow(1 - c, 5);
        }
        case FresnelModel::Dielectric: {
            // Snell: sin^2(theta_t) = sin^2(theta_i) / eta^2; past 1 the light
            // is totally reflected.
            Real n = eta[ch];
            Real sin2t = (1 - c * c) / (n * n);
            if (sin2t >= 1) return 1;
            Real ct = sqrt(1 - sin2t);
            Real rs = (c - n * ct) / (c + n * ct);
            Real rp = (n * c - ct) / (n * c + ct);
            return (rs * rs + rp * rp) / 2;
        }
        case FresnelModel::Conductor: {
            // Complex index N = eta + i k. N cos(theta_t) = sqrt(N^2 - sin^2)
            // (principal root: the transmitted wave decays into the metal).
            std::complex<Real> N(eta[ch], k[ch]);
            std::complex<Real> N2 = N * N;
            std::complex<Real> nct = sqrt(N2 - std::complex<Real>(1 - c * c));
            std::complex<Real> rs = (c - nct) / (c + nct);
            std::complex<Real> rp = (N2 * c - nct) / (N2 * c + nct);
            return (norm(rs) + norm(rp)) / 2;
        }
    }
    internal_error << "unknown fresnel model";
}

template <typename Real>
std::array<Real, 3> ResolvedMaterial<Real>::brdf(const Vec3<Real>& wi, const Vec3<Real>& wo) const {
    using std::exp; using std::sqrt;
    std::array<Real, 3> out{};
    Real ci = wi.z, co = wo.z;
    if (ci <= 0 || co <= 0) return out;
    Vec3<Real> h{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    Real len = sqrt(h.x * h.x + h.y * h.y + h.z * h.z);
    if (len == 0) return out;
    h = {h.x / len, h.y / len, h.z / len};
    Real c = wi.x * h.x + wi.y * h.y + wi.z * h.z;
    if (c > 1) c = 1;
    const Real pi = kPi<Real>;
    if (ndf == NdfModel::Ward) {
        // Ward 1992: exp(-tan^2(theta_h)(cos^2(phi_h)/ax^2 + sin^2(phi_h)/ay^2)) / (4 pi ax ay sqrt(ci co))
        Real e = (sq(h.x / alphaX) + sq(h.y / alphaY)) / sq(h.z);
        Real lobe = exp(-e) / (4 * pi * alphaX * alphaY * sqrt(ci * co));
        for (int ch = 0; ch < 3; ++ch) out[ch] = F(c, ch) * lobe;
    } else {
        Real dg = D(h) * G(wi, wo, h) / (4 * ci * co);
        for (int ch = 0; ch < 3; ++ch) out[ch] = F(c, ch) * dg;
    }
    if (diffuse == DiffuseModel::Lambert)
        for (int ch = 0; ch < 3; ++ch) out[ch] += albedo[ch] / pi;
    return out;
}

template <typename Real>
ResolvedMaterial<Real> Interpreter<Real>::resolve(const Real* slots) const {
    using std::isnan;
    const CheckedMaterial& m = material_;
    ResolvedMaterial<Real> r;
    r.ndf = m.ndfModel();
    r.masking = m.maskingModel();
    r.fresnel = m.fresnelModel();
    r.diffuse = m.diffuseModel();

    // Inputs: given or default, clamped to the declared range.
    std::vector<Value<Real>> inputs(m.inputs.size());
    for (size_t i = 0; i < m.inputs.size(); ++i) {
        const CheckedInput& in = m.inputs[i];
        Value<Real>& v = inputs[i];
        v.rgb = in.type == ValueType::Rgb;
        for (int ch = 0; ch < in.slotCount(); ++ch) {
            Real x = slots ? slots[in.firstSlot + ch] : Real(in.defaultValue[ch]);
            if (!finite(x)) r.valid = false;
            if (in.hasRange) x = x < Real(in.lo) ? Real(in.lo) : (x > Real(in.hi) ? Real(in.hi) : x);
            v.c[ch] = x;
        }
        if (!v.rgb) v.c[1] = v.c[2] = v.c[0];
    }
    std::vector<Value<Real>> lets;
    lets.reserve(m.lets.size());
    auto lookup = [&](const NameExpr& n) -> Value<Real> {
        internal_assert(n.binding != BindingKind::Unresolved) << "unresolved name " << n.name;
        return n.binding == BindingKind::Input ? inputs.at(n.index) : lets.at(n.index);
    };
    for (const CheckedLet& let : m.lets) lets.push_back(evaluateExpr<Real>(*let.value, lookup));

    // A model argument: NaN is invalid; clamping to the domain happens
    // before the finiteness test so that e.g. phong_exponent(0) = inf
    // clamps to the largest exponent instead of failing.
    auto scalarArg = [&](const ModelUse& use, int p, Real lo, Real hi) {
        Value<Real> v = evaluateExpr<Real>(*use.args[p], lookup);
        Real x = v.c[0];
        if (isnan(x)) {
            r.valid = false;
            return Real(0);
        }
        x = x < lo ? lo : (x > hi ? hi : x);
        if (!finite(x)) r.valid = false;
        return x;
    };
    auto rgbArg = [&](const ModelUse& use, int p, Real lo, Real hi) {
        Value<Real> v = evaluateExpr<Real>(*use.args[p], lookup);
        std::array<Real, 3> out;
        for (int ch = 0; ch < 3; ++ch) {
            Real x = v.channel(ch);
            if (isnan(x)) {
                r.valid = false;
                x = 0;
            }
            x = x < lo ? lo : (x > hi ? hi : x);
            if (!finite(x)) r.valid = false;
            out[ch] = x;
        }
        return out;
    };
    const Real inf = std::numeric_limits<Real>::infinity();
    const Real minAlpha = Real(kMinAlpha);
    switch (r.ndf) {
        case NdfModel::Ggx:
        case NdfModel::Beckmann:
        case NdfModel::Ward:
            r.alphaX = scalarArg(m.ndf, param::AlphaX, minAlpha, inf);
            r.alphaY = scalarArg(m.ndf, param::AlphaY, minAlpha, inf);
            break;
        case NdfModel::BlinnPhong: r.exponent = scalarArg(m.ndf, param::Exponent, 0, Real(kMaxPhongExponent)); break;
        case NdfModel::Gtr:
            r.alphaX = r.alphaY = scalarArg(m.ndf, param::GtrAlpha, minAlpha, inf);
            r.gamma = scalarArg(m.ndf, param::GtrGamma, 0, inf);
            break;
        case NdfModel::Gaussian:
            r.alphaX = r.alphaY = scalarArg(m.ndf, param::GaussianAlpha, minAlpha, inf);
            if (r.valid) r.gaussianNorm = gaussianNdfNorm(r.alphaX);
            break;
    }
    if (r.masking == MaskingModel::SchlickSmith) r.schlickK = scalarArg(m.masking, param::SchlickK, 0, 1);
    switch (r.fresnel) {
        case FresnelModel::None: break;
        case FresnelModel::Schlick:
            if (m.fresnel.has(param::F0)) {
                r.f0 = rgbArg(m.fresnel, param::F0, 0, 1);
            } else {
                r.schlickFromEta = true;
                r.eta = rgbArg(m.fresnel, param::SchlickEta, Real(kMinEta), inf);
            }
            break;
        case FresnelModel::Dielectric: r.eta = rgbArg(m.fresnel, param::DielectricEta, Real(kMinEta), inf); break;
        case FresnelModel::Conductor:
            r.eta = rgbArg(m.fresnel, param::ConductorEta, Real(kMinEta), inf);
            r.k = rgbArg(m.fresnel, param::ConductorK, 0, inf);
            break;
    }
    if (r.diffuse == DiffuseModel::Lambert) r.albedo = rgbArg(m.diffuse, param::Albedo, 0, inf);
    return r;
}

template <typename Real>
EvalResult<Real> Interpreter<Real>::eval(const Real wi[3], const Real wo[3], const Real* slots) const {
    using std::abs; using std::sqrt;
    EvalResult<Real> out;
    Vec3<Real> dirs[2];
    const Real* given[2] = {wi, wo};
    for (int d = 0; d < 2; ++d) {
        const Real* w = given[d];
        if (!finite(w[0]) || !finite(w[1]) || !finite(w[2])) {
            out.valid = false;
            return out;
        }
        Real len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (!(abs(len - 1) <= Real(kUnitTolerance))) {
            out.valid = false;
            return out;
        }
        dirs[d] = {w[0] / len, w[1] / len, w[2] / len};
    }
    ResolvedMaterial<Real> r = resolve(slots);
    if (!r.valid) {
        out.valid = false;
        return out;
    }
    out.rgb = r.brdf(dirs[0], dirs[1]);
    // A value that overflows even the reference's range (parameters far
    // outside any physical use) is reported as an invalid lane, never as Inf.
    for (Real v : out.rgb)
        if (!finite(v) || v < 0) {
            out = {};
            out.valid = false;
        }
    return out;
}

template class Interpreter<double>;
template class Interpreter<long double>;
template struct ResolvedMaterial<double>;
template struct ResolvedMaterial<long double>;
template double gaussianNdfNorm<double>(double);
template long double gaussianNdfNorm<long double>(long double);

}  // namespace facet
