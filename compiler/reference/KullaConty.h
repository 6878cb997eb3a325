// KullaConty: multiple-scattering energy compensation (Kulla & Conty 2017),
// SPEC section 3, `energy = kulla_conty`.
//
//   f_ms(wi, wo) = (1 - E(mu_i)) (1 - E(mu_o)) / (pi (1 - E_avg))
//                  * F_avg^2 E_avg / (1 - F_avg (1 - E_avg))
//
// E(mu, alpha) is the directional albedo of the material's specular lobe
// (its NDF and masking) with F = 1, E_avg(alpha) = 2 Int E(mu) mu dmu, and
// F_avg = 2 Int F(mu) mu dmu per channel. The first factor is Kulla-Conty's
// compensation lobe (its cosine-weighted integral over wi is exactly
// 1 - E(mu_o)), the second their coloured term, which is 1 when F = 1.
//
// This header is the pure, dependency-free part (no image I/O): the table
// key of a material, the quadrature that builds an EnergyTable, lookups with
// bilinear interpolation; the Fresnel averages come from the neutral
// numeric/FresnelAverage.h. Disk caching (EXR through
// OpenEXR) lives in compiler/tables/TableCache.h (library facet_tables).
//
// ---- the E table ----------------------------------------------------------
//
// One table per (NDF family, masking[, gtr gamma][, schlick_smith k]). Each
// table stores the complements Ec = 1 - E and EcAvg = 1 - E_avg in float
// (1 - E is what f_ms needs, and near E = 1 it keeps its relative precision,
// which storing E in float would lose).
//
// Grid: kMuCount x kAlphaCount nodes.
//   mu axis:    u = sqrt(mu) * (kMuCount - 1), nodes at mu = (j/(kMuCount-1))^2, so
//               the steep grazing fall-off of E gets most nodes. The node at
//               mu = 0 holds the limit (integrated at mu = 1e-6).
//   alpha axis: v = (sqrt(alpha) - sqrt(kAlphaMin)) / (sqrt(kAlphaMax) - sqrt(kAlphaMin))
//               * (kAlphaCount - 1), i.e. uniform in the perceptual roughness sqrt(alpha).
//               alpha is clamped to [kAlphaMin, kAlphaMax] before the lookup.
// Interpolation: bilinear in (u, v) for Ec, linear in v for EcAvg.
//
// EcAvg is not integrated from the exact E: it is the exact integral
// 2 Int Ec_interp(mu) mu dmu of the piecewise-linear-in-u table row (a
// polynomial per cell, integrated exactly). Because interpolation is linear
// in v too, the linearly interpolated EcAvg equals the integral of the
// bilinearly interpolated Ec at every alpha, not only at the nodes. So the
// compensation lobe integrates to exactly 1 - E_table(mu_o), and the white
// furnace error of the compensated BRDF is exactly the interpolation error
// E_true(mu_o, alpha) - E_table(mu_o, alpha) (measured by tests/energy).
//
// Pairs whose single-scattering lobe is not energy conserving (masking
// `none`, Smith masking with rough Blinn-Phong, schlick_smith with
// heavy-tailed GTR) have E > 1 somewhere: Ec is clamped to >= 0 there (no
// compensation where the lobe already creates energy), so f_ms >= 0 always.
//
// Roughness used for the lookup (energyAlpha):
//   ggx, beckmann: alpha = sqrt(alpha_x alpha_y) (anisotropic materials use the
//                  isotropic table at the geometric-mean roughness: an
//                  approximation, exact when alpha_x = alpha_y);
//   blinn_phong:   alpha = sqrt(2 / (e + 2)) (the Beckmann-equivalent roughness;
//                  the table itself integrates the Blinn-Phong NDF);
//   gtr:           alpha; the table is built for the material's gamma, which
//                  must be a constant (the checker rejects an input-dependent gamma);
//   gaussian:      alpha (radians).
//   schlick_smith: the table is built for the material's k, which must be constant.
//   ward:          not supported (a whole lobe, not a microfacet NDF + masking).
#pragma once

#include "Builtins.h"
#include "Diagnostics.h"
#include "FresnelAverage.h"
#include "Material.h"

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace facet {

// Bumped whenever the table contents would change (grid, quadrature,
// formulas): cached EXR files of another version are rebuilt.
constexpr int kEnergyTableVersion = 3;

// What an E table depends on besides alpha: the NDF, the masking, and the
// values of their tableShapeParams (the NDF's first).
struct EnergyTableKey {
    const NdfEntry* ndf = nullptr;
    const MaskingEntry* masking = nullptr;
    std::vector<double> shape;
    // 0: the lobe's reflection albedo with F = 1 (above). Otherwise the table
    // of a rough dielectric interface (DielectricEnergy.h): E = R + T of the
    // non-absorbing interface seen from the side whose far side has this
    // relative index (eta from outside, 1/eta from inside).
    double interfaceEta = 0;

    // "ggx_smith_height_correlated", "gtr_g1.5_cook_torrance", "ggx_schlick_smith_k0.125",
    // "ggx_smith_height_correlated_interface1.5".
    std::string name() const;
    bool operator==(const EnergyTableKey& o) const {
        return ndf == o.ndf && masking == o.masking && shape == o.shape && interfaceEta == o.interfaceEta;
    }
    bool operator<(const EnergyTableKey& o) const;
};

// Why `energy = kulla_conty` cannot be used with this lobe of the material,
// with where to point the diagnostic; nullopt when it can. Used by the checker.
struct EnergyUnsupported {
    SourceLoc loc;
    std::string message;
};
std::optional<EnergyUnsupported> kullaContyUnsupported(const CheckedMaterial& material, const CheckedLobe& lobe);

// Does the expression depend on an input (directly or through lets)? The
// first input found, or null.
const CheckedInput* inputUsed(const Expr& e, const CheckedMaterial& m, int depth = 0);
// The value of an input-free expression (channel 0).
double constantOf(const Expr& e, const CheckedMaterial& m);

// The table key of a lobe with energy = kulla_conty (gamma / k evaluated as
// constants). The lobe must pass kullaContyUnsupported.
EnergyTableKey energyTableKey(const CheckedMaterial& material, const CheckedLobe& lobe);
// The same for the single lobe of a material that does not combine lobes.
EnergyTableKey energyTableKey(const CheckedMaterial& material);

// Quadrature settings (part of the EXR metadata: a table built with other
// settings is stale).
struct EnergyQuadrature {
    // Defaults: |E - E_fine| < 2.5e-5 against a much finer quadrature (16-point
    // panels half as wide, 16 x 8 azimuth panels) for ggx, beckmann, blinn_phong
    // and gaussian with every masking they allow, alpha in [1e-4, 1], mu in
    // [1e-6, 1]; < 1e-5 for the Smith forms. The table's interpolation error is
    // larger (~5e-4 at worst in [0.05, 1]^2, see tests/energy).
    int thetaPoints = 4;          // Gauss-Legendre points per theta_h panel
    double thetaMaxPanel = 0.2;   // widest theta_h panel (radians)
    double kinkPanel = 1e-3;      // first theta_h panel at the azimuth-cut kinks
    int phiPoints = 4;            // Gauss-Legendre points per azimuth panel
    int phiPanels = 3;            // azimuth panels, halving toward the cut
    double muZero = 1e-6;         // the mu = 0 node is integrated here
    // Interface tables (DielectricEnergy.h): visible normals drawn on a
    // facetGrid x facetGrid midpoint grid of the sampler's (u1, u2).
    int facetGrid = 96;
    std::string describe() const;
};

// An immutable table of Ec = 1 - E(mu, alpha) and EcAvg = 1 - E_avg(alpha).
class EnergyTable {
public:
    static constexpr int kMuCount = 64;
    static constexpr int kAlphaCount = 64;
    static constexpr double kAlphaMin = kMinAlpha;  // 1e-4
    static constexpr double kAlphaMax = 1.0;

    EnergyTableKey key;
    EnergyQuadrature quadrature;
    int muCount = kMuCount, alphaCount = kAlphaCount;
    double alphaMin = kAlphaMin, alphaMax = kAlphaMax;
    std::vector<float> ec;     // alphaCount rows of muCount: ec[ia * muCount + im]
    std::vector<float> ecAvg;  // alphaCount
    double buildMillis = 0;    // time the quadrature took (0 when loaded from disk)
    std::string origin;        // "built", "memory", "disk"

    // Lookup coordinates, clamped to the grid: u in [0, muCount-1], v in [0, alphaCount-1].
    double muCoord(double mu) const;
    double alphaCoord(double alpha) const;
    // The affine map of sqrt(alpha): v = sqrt(alpha) * alphaScale() + alphaOffset().
    double alphaScale() const;
    double alphaOffset() const;
    // Bilinear 1 - E(mu, alpha) and linear 1 - E_avg(alpha) (in double, from the float nodes).
    double ecAt(double mu, double alpha) const;
    double ecAvgAt(double alpha) const;
    // Node positions.
    double muNode(int j) const;
    double alphaNode(int i) const;
    // The Ec row at a fixed alpha (the alpha interpolation done once): for a
    // kernel whose alpha is a constant; ecAt(mu, alpha) is then the linear
    // interpolation of this row at u = muCoord(mu).
    std::vector<float> rowAt(double alpha) const;

    // Checks the shape and values (sizes, finite, within [0, 1]); "" if fine.
    std::string validate() const;
    // Recomputes ecAvg from ec (the exact integral of the interpolated rows).
    void computeAverages();
};

// The grid a key's table is built on: kMuCount x kAlphaCount for a
// reflection table, kInterfaceGrid^2 for an interface's (each of its nodes
// integrates facetGrid^2 sampled facets rather than a panelled quadrature;
// tests/transmission measures the interpolation error this grid leaves).
struct TableGrid {
    int mu, alpha;
};
constexpr int kInterfaceGrid = 32;
TableGrid defaultTableGrid(const EnergyTableKey& key);

// Builds the table by quadrature (threads: 0 = hardware concurrency).
// (The grid defaults (0) to defaultTableGrid(key) over [kAlphaMin, kAlphaMax];
// other grids are for experiments and tests.)
std::shared_ptr<EnergyTable> buildEnergyTable(const EnergyTableKey& key, const EnergyQuadrature& q = {},
                                              int threads = 0, int muCount = 0, int alphaCount = 0,
                                              double alphaMax = EnergyTable::kAlphaMax);

// The directional albedo E(mu, alpha) with F = 1 of the pair (an
// interface key: R + T of the interface), by the table's quadrature
// (double, no clamping, no interpolation).
double directionalAlbedo(const EnergyTableKey& key, double mu, double alpha, const EnergyQuadrature& q = {});

// ---- Fresnel averages: numeric/FresnelAverage.h -----------------------------

// ---- evaluation ---------------------------------------------------------
//
// Recipe for an evaluator (the interpreter follows it in KullaContyEval.h; a
// JIT lowering embeds table->ec and table->ecAvg as constant float arrays):
//   table  = TableCache::getFor(material)            (or buildEnergyTable(energyTableKey(material)))
//   alpha  = energyAlpha (see the header comment; >= 1e-4 after the usual clamps)
//   v      = clamp(sqrt(clamp(alpha, alphaMin, alphaMax)) * alphaScale() + alphaOffset(), 0, alphaCount - 1)
//   i      = min(floor(v), alphaCount - 2), tv = v - i
//   for c in (n.wi, n.wo):
//     u = sqrt(clamp(c, 0, 1)) * (muCount - 1),  j = min(floor(u), muCount - 2),  tu = u - j
//     Ec(c) = lerp(lerp(ec[i*M + j], ec[i*M + j+1], tu), lerp(ec[(i+1)*M + j], ec[(i+1)*M + j+1], tu), tv)
//   EcAvg  = lerp(ecAvg[i], ecAvg[i+1], tv)
//   F_avg  = per channel: none 1; schlick (20 f0 + 1)/21; dielectric / conductor: constant
//            parameters fold to fresnelAverageDielectric / fresnelAverageConductor,
//            per-lane ones use fresnelAverageTables()
//   f_ms   = kullaContyLobe(Ec(n.wi), Ec(n.wo), EcAvg) * kullaContyFresnelTerm(F_avg, EcAvg)
// With alpha constant, EcAvg and (i, tv) fold and rowAt(alpha) replaces the
// two rows (two gathers per direction instead of four).

// F_avg^2 E_avg / (1 - F_avg (1 - E_avg)), with E_avg = 1 - ecAvg; 0 when the
// denominator vanishes.
template <typename Real>
Real kullaContyFresnelTerm(Real favg, Real ecAvg) {
    Real den = 1 - favg * ecAvg;
    if (!(den > 0)) return Real(0);
    return favg * favg * (1 - ecAvg) / den;
}

// The fresnel-free compensation lobe (1 - E(mu_i))(1 - E(mu_o)) / (pi (1 - E_avg)),
// from table values; 0 when EcAvg = 0 (then Ec = 0 too).
template <typename Real>
Real kullaContyLobe(Real ecI, Real ecO, Real ecAvg) {
    if (!(ecAvg > 0)) return Real(0);
    const Real pi = Real(3.141592653589793238462643383279502884L);
    return ecI * ecO / (pi * ecAvg);
}

// Holds (or lazily builds, in memory, on first use) the table of one
// interpreter's material. Thread-safe; shared by copies of the interpreter.
// An interface table not given is kept for the process's lifetime
// (residentInterfaceTable): an interpreter kernel makes an interpreter per
// batch, and such a table takes about a second to build.
class EnergyTableSlot {
public:
    explicit EnergyTableSlot(EnergyTableKey key, std::shared_ptr<const EnergyTable> table = nullptr);
    // The table given at construction, else one built in memory on first call.
    const std::shared_ptr<const EnergyTable>& get();
    const EnergyTableKey& key() const { return key_; }

private:
    EnergyTableKey key_;
    std::once_flag once_;
    std::shared_ptr<const EnergyTable> table_;
};

// The interface table of `key` (interfaceEta != 0), built on the first call
// in this process and kept (thread-safe).
std::shared_ptr<const EnergyTable> residentInterfaceTable(const EnergyTableKey& key);

}  // namespace facet
