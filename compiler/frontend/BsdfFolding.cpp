// BsdfFolding: see BsdfFolding.h.
#include "BsdfFolding.h"

#include "Specialize.h"

#include <cmath>
#include <optional>

namespace facet {
namespace {

// fold()'s answer for a subtree that is 0 everywhere.
constexpr int kNothing = -2;

// The weight's channels when it is a finite constant.
std::optional<std::array<double, 3>> constantWeight(const BsdfNode& n) {
    if (!n.weight || !isConstantExpr(*n.weight)) return std::nullopt;
    std::array<double, 3> w = constantValue(*n.weight);
    for (double c : w)
        if (!std::isfinite(c)) return std::nullopt;
    return w;
}

bool everyChannel(const std::optional<std::array<double, 3>>& w, bool (*test)(double)) {
    return w && test((*w)[0]) && test((*w)[1]) && test((*w)[2]);
}
bool atMostZero(double c) { return c <= 0; }
bool one(double c) { return c == 1; }
bool atLeastOne(double c) { return c >= 1; }

// Builds the folded tree children first, from the root down.
class Folder {
public:
    explicit Folder(const std::vector<BsdfNode>& in) : in_(in) {}

    std::vector<BsdfNode> out;
    bool changed = false;

    // The index in `out` of node i folded, or kNothing.
    int fold(int i) {
        const BsdfNode& n = in_.at(size_t(i));
        std::optional<std::array<double, 3>> w = constantWeight(n);
        switch (n.kind) {
            case BsdfKind::Lobe: return emit(n, -1, -1);
            case BsdfKind::Scale: {
                if (everyChannel(w, atMostZero)) return folded(kNothing);
                int a = fold(n.a);
                if (a == kNothing || everyChannel(w, one)) return folded(a);
                return emit(n, a, -1);
            }
            case BsdfKind::Sum: {
                int a = fold(n.a), b = fold(n.b);
                if (a == kNothing) return folded(b);
                if (b == kNothing) return folded(a);
                return emit(n, a, b);
            }
            case BsdfKind::Mix: {
                if (everyChannel(w, atMostZero)) return folded(fold(n.a));
                if (everyChannel(w, atLeastOne)) return folded(fold(n.b));
                int a = fold(n.a), b = fold(n.b);
                if (a == kNothing && b == kNothing) return folded(kNothing);
                return emit(n, a == kNothing ? asWritten(n.a) : a, b == kNothing ? asWritten(n.b) : b);
            }
            case BsdfKind::Layer: {
                if (everyChannel(w, atMostZero)) return folded(fold(n.b));
                int top = fold(n.a), base = fold(n.b);
                BsdfNode layer = n;
                if (everyChannel(w, atLeastOne)) layer.weight = nullptr, changed = true;
                return emit(layer, top == kNothing ? asWritten(n.a) : top, base == kNothing ? asWritten(n.b) : base);
            }
        }
        return kNothing;
    }

private:
    // A rewrite: the node is replaced by `index` (a folded node or kNothing).
    int folded(int index) {
        changed = true;
        return index;
    }
    int emit(BsdfNode n, int a, int b) {
        n.a = a, n.b = b;
        out.push_back(std::move(n));
        return int(out.size()) - 1;
    }
    // Node i and its subtree unfolded.
    int asWritten(int i) {
        const BsdfNode& n = in_.at(size_t(i));
        int a = n.a >= 0 ? asWritten(n.a) : -1;
        int b = n.b >= 0 ? asWritten(n.b) : -1;
        return emit(n, a, b);
    }

    const std::vector<BsdfNode>& in_;
};

}  // namespace

bool foldBsdfWeights(CheckedMaterial& material) {
    if (!material.combinesLobes()) return false;
    Folder folder(material.bsdf);
    if (folder.fold(int(material.bsdf.size()) - 1) == kNothing || !folder.changed) return false;
    // The lobes still referred to, in source order.
    std::vector<bool> used(material.lobes.size(), false);
    for (const BsdfNode& n : folder.out)
        if (n.kind == BsdfKind::Lobe) used[size_t(n.lobe)] = true;
    std::vector<int> lobeRemap(material.lobes.size(), -1);
    std::vector<CheckedLobe> lobes;
    for (size_t l = 0; l < material.lobes.size(); ++l)
        if (used[l]) lobeRemap[l] = int(lobes.size()), lobes.push_back(std::move(material.lobes[l]));
    for (BsdfNode& n : folder.out)
        if (n.kind == BsdfKind::Lobe) n.lobe = lobeRemap[size_t(n.lobe)];
    material.lobes = std::move(lobes);
    material.bsdf = std::move(folder.out);
    return true;
}

}  // namespace facet
