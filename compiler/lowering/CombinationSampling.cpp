// CombinationSampling: the sample and pdf lane bodies of a combination of
// lobes (see CombinationEmitter.h). Written independently of the
// reference's mixture (compiler/reference/LobeSampling.cpp), which makes the
// same choices: the leaves of the bsdf tree in the same order, each with the
// share factor * albedo(n.wo) (channel mean), floored at 1% of the largest,
// normalized; u0 picks the leaf and is rescaled into it.
#include "CombinationEmitter.h"

#include "Diagnostics.h"
#include "LaneEmitter.h"

#include <optional>

namespace facet {

namespace {

using Vec = std::array<llvm::Value*, 3>;

// The least share a leaf keeps, relative to the largest (as the reference).
constexpr double kMinShare = 0.01;

class MixtureBody {
public:
    MixtureBody(const CheckedMaterial& material, const LoweringPlan& plan, const LoweringOptions& options,
                llvm::IRBuilder<>& b, llvm::Type* laneType, llvm::Module& module, const std::string& tablePrefix)
        : material_(material), plan_(plan), options_(options), b_(b), laneType_(laneType),
          module_(module), tablePrefix_(tablePrefix) {}

    CombinationSampleLanes sample(const Vec& wo, const Vec& u, const std::vector<llvm::Value*>& slots) {
        start(wo, slots);
        MathEmitter& fm = weights_->floatMath();
        MathEmitter& dm = weights_->doubleMath();
        // u in [0, 1), as every sampler checks (here for diffuse lobes too).
        for (llvm::Value* x : u)
            weights_->rejectInput([&] { return b_.CreateNot(b_.CreateAnd(fm.ge(x, fm.c(0.0)), fm.lt(x, fm.c(1.0)))); });
        llvm::Value* u0 = dm.convert(u[0], dm.type());
        // The leaf u0 falls in (the last one takes the rest), and u0
        // rescaled into it, below 1.
        llvm::Value* below = dm.c(0.0);
        std::vector<llvm::Value*> chosen(leaves_.size());
        std::vector<llvm::Value*> rescaled(leaves_.size());
        llvm::Value* taken = llvm::Constant::getNullValue(chosenType());
        for (size_t k = 0; k < leaves_.size(); ++k) {
            llvm::Value* p = probability_[k];
            llvm::Value* inside = k + 1 < leaves_.size() ? dm.lt(u0, dm.add(below, p)) : allOnes();
            chosen[k] = b_.CreateAnd(b_.CreateNot(taken), inside);
            taken = b_.CreateOr(taken, chosen[k]);
            llvm::Value* r = dm.select(dm.gt(p, dm.c(0.0)), dm.div(dm.sub(u0, below), p), dm.c(0.0));
            r = fm.convert(dm.maxnum(r, dm.c(0.0)), fm.type());
            rescaled[k] = fm.minnum(r, fm.c(0.99999994));  // the largest float below 1
            below = dm.add(below, p);
        }
        // Each leaf's sample (every lane computes every leaf: lanes differ in
        // their choice), then the chosen one.
        Vec wi = {fm.c(0.0), fm.c(0.0), fm.c(0.0)};
        llvm::Value* invalid = llvm::Constant::getNullValue(chosenType());
        for (size_t k = 0; k < leaves_.size(); ++k) {
            const Leaf& leaf = leaves_[k];
            Vec wiK;
            llvm::Value* invalidK = llvm::Constant::getNullValue(chosenType());
            if (leaf.hasNdf) {
                LaneEmitter lanes(lobe(leaf).material, lobe(leaf).plan, body(leaf), energyTable(leaf), b_, laneType_,
                                  module_);
                LaneEmitter::SampleResult r = lanes.emitSample(wo, {rescaled[k], u[1], u[2]}, slots);
                wiK = r.wi;
                invalidK = r.invalid;
            } else {
                // The cosine lobe: sqrt(u1) in the unit disk at azimuth 2 pi u2.
                llvm::Value* u1 = dm.convert(u[1], dm.type());
                llvm::Value* radius = dm.sqrt(u1);
                auto [sinPhi, cosPhi] = dm.sinCosTurns(dm.convert(u[2], dm.type()));
                Vec d = {dm.mul(radius, cosPhi), dm.mul(radius, sinPhi), dm.sqrt(dm.sub(dm.c(1.0), u1))};
                for (int i = 0; i < 3; ++i) wiK[i] = fm.convert(d[i], fm.type());
            }
            for (int i = 0; i < 3; ++i) wi[i] = fm.select(chosen[k], wiK[i], wi[i]);
            invalid = b_.CreateOr(invalid, b_.CreateAnd(chosen[k], invalidK));
        }
        // No sample where wo is below the horizon or no leaf has a share.
        llvm::Value* none = b_.CreateOr(b_.CreateNot(above_), dm.le(total_, dm.c(0.0)));
        for (llvm::Value*& x : wi) x = fm.select(none, fm.c(0.0), x);

        // The density and f at the sample; lanes without one read n (a unit
        // direction), and their outputs are 0 below.
        Vec wiEval = {fm.select(none, fm.c(0.0), wi[0]), fm.select(none, fm.c(0.0), wi[1]),
                      fm.select(none, fm.c(1.0), wi[2])};
        CombinationPdfLanes pdf = mixturePdf(wiEval, wo, slots);
        CombinationLanes f = emitCombination(material_, plan_, options_, false, b_, laneType_, module_, wiEval, wo,
                                             slots, tablePrefix_);
        CombinationSampleLanes out;
        out.wi = wi;
        out.pdf = fm.convert(pdf.pdf, fm.type());
        llvm::Value* weighted = b_.CreateAnd(b_.CreateNot(none), b_.CreateAnd(fm.gt(out.pdf, fm.c(0.0)),
                                                                                fm.gt(wi[2], fm.c(0.0))));
        llvm::Value* cosOverPdf = dm.div(dm.convert(wi[2], dm.type()), pdf.pdf);
        for (int ch = 0; ch < 3; ++ch) {
            llvm::Value* w = dm.mul(dm.convert(f.rgb[ch], dm.type()), cosOverPdf);
            out.weight[ch] = fm.select(weighted, fm.convert(w, fm.type()), fm.c(0.0));
        }
        invalid = b_.CreateOr(b_.CreateOr(invalid, weights_->invalidLanes()), b_.CreateOr(pdf.invalid, f.invalid));
        invalid = b_.CreateOr(invalid, fm.anyNanInfOrNegative({out.pdf, out.weight[0], out.weight[1], out.weight[2]}));
        llvm::Value* zero = b_.CreateOr(invalid, none);
        for (llvm::Value*& x : out.wi) x = fm.select(zero, fm.c(0.0), x);
        out.pdf = fm.select(zero, fm.c(0.0), out.pdf);
        for (llvm::Value*& x : out.weight) x = fm.select(zero, fm.c(0.0), x);
        out.invalid = invalid;
        return out;
    }

    CombinationPdfLanes pdf(const Vec& wi, const Vec& wo, const std::vector<llvm::Value*>& slots) {
        start(wo, slots);
        CombinationPdfLanes r = mixturePdf(wi, wo, slots);
        MathEmitter& fm = weights_->floatMath();
        llvm::Value* invalid = b_.CreateOr(r.invalid, weights_->invalidLanes());
        llvm::Value* p = fm.convert(r.pdf, fm.type());
        invalid = b_.CreateOr(invalid, fm.isNanInfOrNegative(p));
        return {fm.select(invalid, fm.c(0.0), p), invalid};
    }

private:
    struct Leaf {
        int node, lobe;
        bool hasNdf;
        std::array<llvm::Value*, 3> factor;  // double
    };

    const LobeLowering& lobe(const Leaf& leaf) const { return *plan_.lobes.at(size_t(leaf.lobe)); }
    const BodyPlan& body(const Leaf& leaf) const { return lobe(leaf).plan.sampling.body; }
    const EnergyTable* energyTable(const Leaf& leaf) const { return lobeEnergyTable(options_, size_t(leaf.lobe)); }
    llvm::Type* chosenType() { return weights_->invalidLanes()->getType(); }
    llvm::Value* allOnes() { return llvm::Constant::getAllOnesValue(chosenType()); }

    // The weights, n.wo, the leaves and their probabilities.
    void start(const Vec& wo, const std::vector<llvm::Value*>& slots) {
        expressions_.emplace(plan_, b_, laneType_, module_, slots);
        weights_ = &expressions_->lanes();
        MathEmitter& dm = weights_->doubleMath();
        muO_ = unitCosine(*weights_, wo);
        above_ = dm.gt(muO_, dm.c(0.0));
        collect(int(material_.bsdf.size()) - 1, {dm.c(1.0), dm.c(1.0), dm.c(1.0)});
        // Shares, floored at 1% of the largest (a leaf whose factor is 0 in
        // every channel keeps 0), normalized; equal where every share is 0.
        std::vector<llvm::Value*> share, live;
        llvm::Value* top = dm.c(0.0);
        for (const Leaf& leaf : leaves_) {
            std::array<llvm::Value*, 3> a;
            if (const MuTable* t = plan_.nodeAlbedo.at(size_t(leaf.node)).get())
                a = lookUpMuTable(*weights_, *t, tablePrefix_ + ".albedo" + std::to_string(leaf.node), muO_);
            else
                a = {dm.c(1.0), dm.c(1.0), dm.c(1.0)};  // no estimate (invalid defaults): the factors alone
            llvm::Value* s = dm.c(0.0);
            llvm::Value* any = nullptr;
            for (int ch = 0; ch < 3; ++ch) {
                s = dm.fma(leaf.factor[ch], dm.mul(dm.maxnum(a[ch], dm.c(0.0)), dm.c(1.0 / 3)), s);
                llvm::Value* positive = dm.gt(leaf.factor[ch], dm.c(0.0));
                any = any ? b_.CreateOr(any, positive) : positive;
            }
            s = dm.select(dm.isFinite(s), s, dm.c(0.0));
            share.push_back(s);
            live.push_back(any);
            top = dm.select(any, dm.maxnum(top, s), top);
        }
        llvm::Value* someShare = dm.gt(top, dm.c(0.0));
        total_ = dm.c(0.0);
        for (size_t k = 0; k < leaves_.size(); ++k) {
            llvm::Value* floored = dm.select(someShare, dm.maxnum(share[k], dm.mul(top, dm.c(kMinShare))), dm.c(1.0));
            share[k] = dm.select(live[k], floored, dm.c(0.0));
            total_ = dm.add(total_, share[k]);
        }
        for (size_t k = 0; k < leaves_.size(); ++k)
            probability_.push_back(dm.select(dm.gt(total_, dm.c(0.0)), dm.div(share[k], total_), dm.c(0.0)));
    }

    // The leaves under `node` and the rgb factor the tree gives each.
    void collect(int node, const std::array<llvm::Value*, 3>& factor) {
        const BsdfNode& n = material_.bsdf.at(size_t(node));
        MathEmitter& dm = weights_->doubleMath();
        auto times = [&](const LVal& w) {
            return std::array<llvm::Value*, 3>{dm.mul(factor[0], w.c[0]), dm.mul(factor[1], w.c[1]),
                                               dm.mul(factor[2], w.c[2])};
        };
        auto oneMinus = [&](const LVal& w) {
            LVal r = w;
            for (llvm::Value*& x : r.c) x = dm.sub(dm.c(1.0), x);
            return r;
        };
        switch (n.kind) {
            case BsdfKind::Lobe:
                leaves_.push_back({node, n.lobe, material_.lobes.at(size_t(n.lobe)).hasNdf(), factor});
                return;
            case BsdfKind::Scale: collect(n.a, times(weights_->clampedExpression(*n.weight, 0, INFINITY))); return;
            case BsdfKind::Sum:
                collect(n.a, factor);
                collect(n.b, factor);
                return;
            case BsdfKind::Mix: {
                LVal w = weights_->clampedExpression(*n.weight, 0, 1);
                collect(n.a, times(oneMinus(w)));
                collect(n.b, times(w));
                return;
            }
            case BsdfKind::Layer: {
                LVal w = n.weight ? weights_->clampedExpression(*n.weight, 0, 1) : LVal::scalar(dm.c(1.0));
                collect(n.a, times(w));
                // The base: 1 - W + W u(n.wo), u = 1 - E_top.
                LVal base = oneMinus(w);
                if (const MuTable* t = plan_.nodeAlbedo.at(size_t(node)).get()) {
                    std::array<llvm::Value*, 3> eTop =
                        lookUpMuTable(*weights_, *t, tablePrefix_ + ".albedo" + std::to_string(node), muO_);
                    for (int ch = 0; ch < 3; ++ch)
                        base.c[ch] = dm.fma(w.c[ch], dm.maxnum(dm.sub(dm.c(1.0), eTop[ch]), dm.c(0.0)), base.c[ch]);
                }
                collect(n.b, times(base));
                return;
            }
        }
    }

    // sum_k p_k pdf_k(wi): each lobe's own density (its one-lobe pdf; the
    // cosine lobe for a diffuse lobe).
    CombinationPdfLanes mixturePdf(const Vec& wi, const Vec& wo, const std::vector<llvm::Value*>& slots) {
        MathEmitter& dm = weights_->doubleMath();
        llvm::Value* pdf = dm.c(0.0);
        llvm::Value* invalid = llvm::Constant::getNullValue(chosenType());
        llvm::Value* cosine = nullptr;
        for (size_t k = 0; k < leaves_.size(); ++k) {
            const Leaf& leaf = leaves_[k];
            llvm::Value* pk;
            if (leaf.hasNdf) {
                LaneEmitter lanes(lobe(leaf).material, lobe(leaf).plan, body(leaf), energyTable(leaf), b_, laneType_,
                                  module_);
                LaneEmitter::PdfResult r = lanes.emitPdf(wi, wo, slots);
                pk = dm.convert(r.pdf, dm.type());
                invalid = b_.CreateOr(invalid, r.invalid);
            } else {
                if (!cosine) {
                    llvm::Value* z = unitCosine(*weights_, wi);
                    cosine = dm.select(dm.gt(z, dm.c(0.0)), dm.mul(z, dm.c(1.0 / kPi)), dm.c(0.0));
                }
                pk = cosine;
            }
            pdf = dm.fma(probability_[k], pk, pdf);
        }
        pdf = dm.select(above_, pdf, dm.c(0.0));
        return {pdf, invalid};
    }

    const CheckedMaterial& material_;
    const LoweringPlan& plan_;
    const LoweringOptions& options_;
    llvm::IRBuilder<>& b_;
    llvm::Type* laneType_;
    llvm::Module& module_;
    std::string tablePrefix_;
    std::optional<CombinationExpressions> expressions_;
    LaneEmitter* weights_ = nullptr;
    llvm::Value *muO_ = nullptr, *above_ = nullptr, *total_ = nullptr;
    std::vector<Leaf> leaves_;
    std::vector<llvm::Value*> probability_;  // double, per leaf
};

}  // namespace

CombinationSampleLanes emitCombinationSample(const CheckedMaterial& material, const LoweringPlan& plan,
                                             const LoweringOptions& options, llvm::IRBuilder<>& builder,
                                             llvm::Type* laneType, llvm::Module& module, const Vec& wo, const Vec& u,
                                             const std::vector<llvm::Value*>& slots, const std::string& tablePrefix) {
    internal_assert(plan.combines() && plan.sampling.compiled) << "a combination sampler the plan did not plan";
    return MixtureBody(material, plan, options, builder, laneType, module, tablePrefix).sample(wo, u, slots);
}

CombinationPdfLanes emitCombinationPdf(const CheckedMaterial& material, const LoweringPlan& plan,
                                       const LoweringOptions& options, llvm::IRBuilder<>& builder,
                                       llvm::Type* laneType, llvm::Module& module, const Vec& wi, const Vec& wo,
                                       const std::vector<llvm::Value*>& slots, const std::string& tablePrefix) {
    internal_assert(plan.combines() && plan.sampling.compiled) << "a combination pdf the plan did not plan";
    return MixtureBody(material, plan, options, builder, laneType, module, tablePrefix).pdf(wi, wo, slots);
}

}  // namespace facet
