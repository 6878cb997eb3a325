// LayerAlbedo: the reference's tables for layer(TOP, BASE [, weight = W])
// (SPEC 10; docs/design-notes/layer-albedo-scaling.md).
//
//   f = W f_top + (1 - W + W g(mu_i) g(mu_o)) f_base
//
// u(mu) = 1 - E_top(mu) per channel (E_top: the top sub-expression's
// directional albedo, its Fresnel included). A Lambertian base (a tree of
// diffuse lobes with no layer in it) has g = u / sqrt(1 - Ebar_top); any
// other base has the g that solves the balance
//   g(mu_o) Int g(mu_i) f_base mu_i dw_i = u(mu_o) A_b(mu_o)
// by the note's symmetric Sinkhorn iteration, the base taken with Fresnel 1
// in its lobes (NDF, masking and Kulla-Conty kept, F_avg 1).
//
// Tables hold 65 nodes, mu_j = (e^{6 x_j} - 1)/(e^6 - 1), x_j = j/64 (node 0
// integrated at mu = 1e-4), read by linear interpolation in x with mu
// clamped to [1e-4, 1]. They are computed here by the reference's own
// quadrature over the half vector (no code shared with the lowering), in
// double, and cached per resolved parameter set (a bounded, mutex-protected
// map), so that a batch of evaluations with the same parameters bakes once.
#pragma once

#include "Interpreter.h"

#include <array>
#include <memory>

namespace facet {

// One rgb value per node of the layer grid.
struct MuTable {
    static constexpr int kNodes = 65;
    static constexpr double kMuMin = 1e-4;
    std::array<std::array<double, 3>, kNodes> v{};
    // Linear interpolation in x at mu (clamped to [kMuMin, 1]).
    std::array<double, 3> at(double mu) const;
    // mu of node j (node 0 is mu = 0; it is integrated at kMuMin).
    static double nodeMu(int j);
};

// The same resolved combination in double (what the tables are baked from).
template <typename Real>
ResolvedMaterial<double> lobeToDouble(const ResolvedMaterial<Real>& r) {
    ResolvedMaterial<double> d;
    d.valid = r.valid;
    d.ndf = r.ndf, d.masking = r.masking, d.fresnel = r.fresnel, d.energy = r.energy, d.diffuse = r.diffuse;
    d.ndfArgs = convertArgs<double>(r.ndfArgs);
    d.maskingArgs = convertArgs<double>(r.maskingArgs);
    d.fresnelArgs = convertArgs<double>(r.fresnelArgs);
    d.diffuseArgs = convertArgs<double>(r.diffuseArgs);
    d.energyTable = r.energyTable;
    d.energyAlpha = double(r.energyAlpha), d.ecAvg = double(r.ecAvg);
    for (int ch = 0; ch < 3; ++ch) d.favg[ch] = double(r.favg[ch]);
    return d;
}
template <typename Real>
ResolvedBsdf<double> bsdfToDouble(const ResolvedBsdf<Real>& r) {
    ResolvedBsdf<double> d;
    d.valid = r.valid;
    for (const ResolvedMaterial<Real>& l : r.lobes) d.lobes.push_back(lobeToDouble(l));
    for (const std::array<Real, 3>& w : r.weights) d.weights.push_back({double(w[0]), double(w[1]), double(w[2])});
    return d;
}

// g of the layer node `layer` of m (BsdfKind::Layer), per channel; cached.
std::shared_ptr<const MuTable> layerG(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int layer);
// The directional albedo Int f(wi, wo) mu_i dwi of the sub-expression
// `node` at the nodes, its own Fresnel included; cached.
std::shared_ptr<const MuTable> albedoTable(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node);
// The layer's g at two cosines: S = g(mu_i) g(mu_o) per channel.
std::array<double, 3> layerScale(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int layer, double muI,
                                 double muO);

}  // namespace facet
