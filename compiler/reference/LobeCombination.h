// LobeCombination: the reference BRDF of a combination of lobes (SPEC 10):
// the tree of CheckedMaterial::bsdf evaluated node by node over the
// resolved lobes. Used by Interpreter::combinedBrdf in every real type and,
// in double, by the layer's quadrature (LayerAlbedo.cpp), which integrates
// sub-expressions with it.
#pragma once

#include "Interpreter.h"
#include "LayerAlbedo.h"

#include <array>

namespace facet {

template <typename Real>
class CombinationEval {
public:
    // `rd`: the same resolved combination in double, for the layers' tables
    // (null when the combination has no layer).
    CombinationEval(const CheckedMaterial& m, const ResolvedBsdf<Real>& r, const ResolvedBsdf<double>* rd,
                    const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& sum)
        : m_(m), r_(r), rd_(rd), wi_(wi), wo_(wo), sum_(sum) {}

    std::array<Real, 3> node(int index) const {
        const BsdfNode& n = m_.bsdf.at(size_t(index));
        const std::array<Real, 3>& w = r_.weights.at(size_t(index));
        std::array<Real, 3> out{};
        switch (n.kind) {
            case BsdfKind::Lobe: return r_.lobes.at(size_t(n.lobe)).brdf(wi_, wo_, sum_);
            case BsdfKind::Scale: {
                std::array<Real, 3> x = node(n.a);
                for (int ch = 0; ch < 3; ++ch) out[ch] = w[ch] == 0 ? Real(0) : w[ch] * x[ch];
                return out;
            }
            case BsdfKind::Sum: {
                std::array<Real, 3> x = node(n.a), y = node(n.b);
                for (int ch = 0; ch < 3; ++ch) out[ch] = x[ch] + y[ch];
                return out;
            }
            case BsdfKind::Mix: {
                std::array<Real, 3> x = node(n.a), y = node(n.b);
                for (int ch = 0; ch < 3; ++ch) out[ch] = (1 - w[ch]) * x[ch] + w[ch] * y[ch];
                return out;
            }
            case BsdfKind::Layer: return layer(index, n, w);
        }
        return out;
    }

private:
    // W f_top + (1 - W + W S) f_base. W = 0 needs no table (the base alone);
    // below the horizon both terms are 0 and no table is read either.
    std::array<Real, 3> layer(int index, const BsdfNode& n, const std::array<Real, 3>& w) const {
        std::array<Real, 3> base = node(n.b), out{};
        bool coated = w[0] > 0 || w[1] > 0 || w[2] > 0;
        if (!coated || !(wi_.z > 0) || !(wo_.z > 0)) {
            for (int ch = 0; ch < 3; ++ch) out[ch] = coated ? Real(0) : base[ch];
            return out;
        }
        std::array<Real, 3> top = node(n.a);
        std::array<double, 3> s = layerScale(m_, *rd_, index, double(wi_.z), double(wo_.z));
        for (int ch = 0; ch < 3; ++ch) {
            Real scale = 1 - w[ch] + w[ch] * Real(s[ch]);
            out[ch] = (w[ch] == 0 ? Real(0) : w[ch] * top[ch]) + (scale == 0 ? Real(0) : scale * base[ch]);
        }
        return out;
    }

    const CheckedMaterial& m_;
    const ResolvedBsdf<Real>& r_;
    const ResolvedBsdf<double>* rd_;
    const Vec3<Real>&wi_, &wo_, &sum_;
};

// Does the combination contain a layer (then evaluation needs the double form)?
bool hasLayer(const CheckedMaterial& m);

}  // namespace facet
