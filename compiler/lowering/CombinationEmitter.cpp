// CombinationEmitter: the lane body of a combination of lobes (see
// CombinationEmitter.h).
#include "CombinationEmitter.h"

#include "Diagnostics.h"
#include "LaneEmitter.h"
#include "LayerAlbedo.h"

#include <bit>
#include <cmath>
#include <optional>

namespace facet {


namespace {

class CombinationBody {
public:
    CombinationBody(const CheckedMaterial& material, const LoweringPlan& plan, const LoweringOptions& options,
                    bool guarded, llvm::IRBuilder<>& b, llvm::Type* laneType, llvm::Module& module,
                    const std::string& tablePrefix)
        : material_(material), plan_(plan), options_(options), guarded_(guarded), b_(b), laneType_(laneType),
          module_(module), tablePrefix_(tablePrefix) {}

    CombinationLanes emit(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                          const std::vector<llvm::Value*>& slots) {
        // Every lobe by the one-lobe emitter; each checks the directions and
        // the inputs its models read, and gives 0 for its invalid lanes.
        llvm::Value* invalid = nullptr;
        llvm::Value* untrusted = nullptr;
        for (size_t l = 0; l < plan_.lobes.size(); ++l) {
            const LobeLowering& lobe = *plan_.lobes[l];
            const EnergyTable* table = lobeEnergyTable(options_, l);
            internal_assert(!lobe.plan.compensatesEnergy || table) << "lobe " << l << " without its energy table";
            const BodyPlan& body = guarded_ ? lobe.plan.batchBody : lobe.plan.scalarBody;
            internal_assert(guarded_ || !body.guarded()) << "a plain combination body with a guarded lobe";
            LaneEmitter lanes(lobe.material, lobe.plan, body, table, b_, laneType_, module_);
            LaneEmitter::Result r = lanes.emit(wi, wo, slots);
            lobeValues_.push_back(r.rgb);
            invalid = invalid ? b_.CreateOr(invalid, r.invalid) : r.invalid;
            untrusted = untrusted ? b_.CreateOr(untrusted, r.untrusted) : r.untrusted;
        }
        expressions_.emplace(plan_, b_, laneType_, module_, slots);
        weights_ = &expressions_->lanes();
        wiZ_ = unitCosine(*weights_, wi), woZ_ = unitCosine(*weights_, wo);

        MathEmitter& fm = weights_->floatMath();
        std::array<llvm::Value*, 3> fd = node(int(material_.bsdf.size()) - 1), f;
        for (int ch = 0; ch < 3; ++ch) f[ch] = fm.convert(fd[ch], fm.type());
        invalid = b_.CreateOr(invalid, weights_->invalidLanes());
        // Sums of finite float values can still overflow.
        invalid = b_.CreateOr(invalid, fm.anyNanInfOrNegative({f[0], f[1], f[2]}));
        for (llvm::Value*& x : f) x = fm.select(invalid, fm.c(0.0), x);
        // A guarded body's invalid lanes are untrusted: the plain bodies
        // decide their validity.
        return {f, invalid, b_.CreateOr(untrusted, invalid)};
    }

private:
    using Rgb = std::array<llvm::Value*, 3>;

    // The combination in double: a mix's (1 - w) and a layer's 1 - W + W S
    // would lose the accuracy of a weight near 1 in float.
    Rgb node(int index) {
        const BsdfNode& n = material_.bsdf.at(size_t(index));
        MathEmitter& dm = weights_->doubleMath();
        switch (n.kind) {
            case BsdfKind::Lobe: {
                const Rgb& f = lobeValues_.at(size_t(n.lobe));
                return channels([&](int ch) { return dm.convert(f[ch], dm.type()); });
            }
            case BsdfKind::Scale: {
                Rgb x = node(n.a);
                LVal w = weights_->clampedExpression(*n.weight, 0, INFINITY);
                // A zero weight gives 0 even where the lobe is large (no 0 * Inf).
                return channels([&](int ch) {
                    return dm.select(dm.eq(w.c[ch], dm.c(0.0)), dm.c(0.0), dm.mul(w.c[ch], x[ch]));
                });
            }
            case BsdfKind::Sum: {
                Rgb x = node(n.a), y = node(n.b);
                return channels([&](int ch) { return dm.add(x[ch], y[ch]); });
            }
            case BsdfKind::Mix: {
                Rgb x = node(n.a), y = node(n.b);
                LVal w = weights_->clampedExpression(*n.weight, 0, 1);
                return channels(
                    [&](int ch) { return dm.fma(w.c[ch], y[ch], dm.mul(dm.sub(dm.c(1.0), w.c[ch]), x[ch])); });
            }
            case BsdfKind::Layer: return layer(index, n);
        }
        internal_error << "unknown combination node";
    }

    template <typename F>
    static Rgb channels(F f) {
        return {f(0), f(1), f(2)};
    }

    // W f_top + (1 - W + W g(mu_i) g(mu_o)) f_base (LayerAlbedo.h). Below
    // the horizon both lobes are 0, and so is f; the table is read at the
    // clamped cosine there, harmlessly.
    Rgb layer(int index, const BsdfNode& n) {
        MathEmitter& dm = weights_->doubleMath();
        Rgb top = node(n.a), base = node(n.b);
        LVal w = n.weight ? weights_->clampedExpression(*n.weight, 0, 1) : LVal::scalar(dm.c(1.0));
        const MuTable* g = plan_.layerG.at(size_t(index)).get();
        internal_assert(g) << "layer node " << index << " without its table";
        const std::string name = tablePrefix_ + ".layer" + std::to_string(index);
        std::array<llvm::Value*, 3> gi = lookUpMuTable(*weights_, *g, name, wiZ_),
                                    go = lookUpMuTable(*weights_, *g, name, woZ_);
        return channels([&](int ch) {
            llvm::Value* scale = dm.fma(w.c[ch], dm.sub(dm.mul(gi[ch], go[ch]), dm.c(1.0)), dm.c(1.0));
            llvm::Value* coat = dm.select(dm.eq(w.c[ch], dm.c(0.0)), dm.c(0.0), dm.mul(w.c[ch], top[ch]));
            return dm.fma(scale, base[ch], coat);
        });
    }

    const CheckedMaterial& material_;
    const LoweringPlan& plan_;
    const LoweringOptions& options_;
    bool guarded_;
    llvm::IRBuilder<>& b_;
    llvm::Type* laneType_;
    llvm::Module& module_;
    std::string tablePrefix_;
    std::vector<Rgb> lobeValues_;
    std::optional<CombinationExpressions> expressions_;
    LaneEmitter* weights_ = nullptr;
    llvm::Value *wiZ_ = nullptr, *woZ_ = nullptr;
};

}  // namespace

CombinationExpressions::CombinationExpressions(const LoweringPlan& combination, llvm::IRBuilder<>& builder,
                                               llvm::Type* laneType, llvm::Module& module,
                                               const std::vector<llvm::Value*>& slots)
    : plan_(combination.lobes.at(0)->plan), body_(plan_.scalarBody) {
    plan_.reads = combination.reads;
    body_.expressions = Precision::Double;
    lanes_ = std::make_unique<LaneEmitter>(combination.lobes[0]->material, plan_, body_, nullptr, builder, laneType,
                                           module);
    lanes_->lowerExpressions(slots);
}

CombinationExpressions::~CombinationExpressions() = default;

const EnergyTable* lobeEnergyTable(const LoweringOptions& options, size_t lobe) {
    return lobe < options.lobeEnergyTables.size() ? options.lobeEnergyTables[lobe] : nullptr;
}

llvm::Value* unitCosine(LaneEmitter& lanes, const std::array<llvm::Value*, 3>& w) {
    MathEmitter& dm = lanes.doubleMath();
    llvm::Value *x = dm.convert(w[0], dm.type()), *y = dm.convert(w[1], dm.type()), *z = dm.convert(w[2], dm.type());
    llvm::Value* len2 = dm.fma(x, x, dm.fma(y, y, dm.mul(z, z)));
    return dm.div(z, dm.sqrt(len2));
}

std::array<llvm::Value*, 3> lookUpMuTable(LaneEmitter& lanes, const MuTable& table, const std::string& name,
                                          llvm::Value* mu) {
    MathEmitter& dm = lanes.doubleMath();
    llvm::IRBuilder<>& b = lanes.builder;
    const int intervals = MuTable::kNodes - 1;
    // Gray: one channel of lookups.
    bool gray = true;
    for (const auto& node : table.v) gray = gray && node[0] == node[1] && node[1] == node[2];
    const int channels = gray ? 1 : 3;
    // Interval j's two nodes packed into one 64-bit element (node j's value
    // in the low half, as floats), so that a channel takes one gather of
    // 64-bit elements instead of two of doubles: a gather costs per element
    // loaded, about 3 cycles each on Zen 5 (docs/perf-log.md). Float nodes
    // move g by at most 6e-8 relative.
    std::vector<uint64_t> pairs;
    for (int ch = 0; ch < channels; ++ch)
        for (int j = 0; j < intervals; ++j) {
            const float lo = float(table.v[size_t(j)][size_t(ch)]), hi = float(table.v[size_t(j) + 1][size_t(ch)]);
            pairs.push_back(uint64_t(std::bit_cast<uint32_t>(hi)) << 32 | std::bit_cast<uint32_t>(lo));
        }
    llvm::GlobalVariable* gv = lanes.uint64Table(pairs, name);
    // The interval and the position in it in double, as the reference finds
    // them: t runs to 64, and in float its rounding alone moves g by up to
    // ~1e-5 where the table is steep (tried: 1.5e-5 in the lobes' differential
    // test, beyond exact mode's bound). log(1 + mu (e^6 - 1)) rather than
    // log1p: the argument is at least 1.04, so rounding it costs nothing, and
    // log1p's correction would cost a division.
    llvm::Value* m = dm.minnum(dm.maxnum(dm.convert(mu, dm.type()), dm.c(MuTable::kMuMin)), dm.c(1.0));
    llvm::Value* x = dm.mul(dm.log(dm.fma(m, dm.c(std::expm1(6.0)), dm.c(1.0))), dm.c(1.0 / 6));
    llvm::Value* t = dm.mul(x, dm.c(double(intervals)));
    llvm::Value* j = dm.minnum(lanes.intrinsic(llvm::Intrinsic::floor, t), dm.c(intervals - 1.0));
    llvm::Value* s = dm.sub(t, j);
    const unsigned width = unsigned(dm.width());
    auto vec = [&](llvm::Type* t) -> llvm::Type* { return width > 1 ? llvm::FixedVectorType::get(t, width) : t; };
    llvm::Type* i64 = b.getInt64Ty();
    llvm::Type* i32s = vec(b.getInt32Ty());
    llvm::Type* floats = vec(b.getFloatTy());
    llvm::Value* idx = b.CreateFPToSI(j, i32s);
    std::array<llvm::Value*, 3> out{};
    for (int ch = 0; ch < channels; ++ch) {
        llvm::Value* ptr = b.CreateGEP(i64, gv, b.CreateAdd(idx, llvm::ConstantInt::get(i32s, ch * intervals)));
        llvm::Value* pair =
            width > 1 ? (llvm::Value*)b.CreateMaskedGather(vec(i64), ptr, llvm::Align(8)) : b.CreateLoad(i64, ptr);
        llvm::Value* lo = dm.convert(b.CreateBitCast(b.CreateTrunc(pair, i32s), floats), dm.type());
        llvm::Value* hi = b.CreateLShr(pair, llvm::ConstantInt::get(pair->getType(), 32));
        hi = dm.convert(b.CreateBitCast(b.CreateTrunc(hi, i32s), floats), dm.type());
        out[size_t(ch)] = dm.fma(s, dm.sub(hi, lo), lo);
    }
    if (gray) out[1] = out[2] = out[0];
    return out;
}

CombinationLanes emitCombination(const CheckedMaterial& material, const LoweringPlan& plan,
                                 const LoweringOptions& options, bool guarded, llvm::IRBuilder<>& builder,
                                 llvm::Type* laneType, llvm::Module& module, const std::array<llvm::Value*, 3>& wi,
                                 const std::array<llvm::Value*, 3>& wo, const std::vector<llvm::Value*>& slots,
                                 const std::string& tablePrefix) {
    internal_assert(plan.combines()) << "emitCombination of a one-lobe plan";
    return CombinationBody(material, plan, options, guarded, builder, laneType, module, tablePrefix)
        .emit(wi, wo, slots);
}

}  // namespace facet
