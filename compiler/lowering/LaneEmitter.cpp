// LaneEmitter: the checked directions and half vector of a lane, and the
// assembly of f from the model terms (see LaneEmitter.h).
#include "LaneEmitter.h"

#include "Diagnostics.h"

#include <llvm/IR/MDBuilder.h>

#include <cfloat>

namespace facet {

using llvm::Value;

namespace {

llvm::Type* doubleOf(llvm::IRBuilder<>& b, llvm::Type* laneType) {
    if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(laneType))
        return llvm::FixedVectorType::get(b.getDoubleTy(), vt->getNumElements());
    return b.getDoubleTy();
}

}  // namespace

LaneEmitter::LaneEmitter(const CheckedMaterial& material, const LoweringPlan& plan, const BodyPlan& body,
                         const EnergyTable* energyTable, llvm::IRBuilder<>& builder, llvm::Type* laneType,
                         llvm::Module& module, const EnergyTable* energyTableInside)
    : material(material), plan(plan), body(body), builder(builder), energyTable_(energyTable),
      energyTableInside_(energyTableInside), module_(module),
      emitters_(termEmitters(material)), floatMath_(builder, laneType, body.shortPolynomials),
      preciseMath_(builder, body.precise == Precision::Double ? doubleOf(builder, laneType) : laneType,
                   body.shortPolynomials),
      doubleMath_(builder, doubleOf(builder, laneType)) {
    internal_assert(!body.guarded() || body.precise == Precision::Float)
        << "a guarded body is the float body of an exact kernel or the body of a fast one";
    invalid_ = llvm::Constant::getNullValue(boolType());
    untrusted_ = invalid_;
    if (body.estimates) {
        // Lets the backend replace x/sqrt(y) by an rsqrt estimate plus a
        // Newton step (the kernel's "reciprocal-estimates" attribute). No
        // nnan/ninf: the NaN and overflow checks must stay exact. Without
        // ninf LLVM keeps the other divisions and square roots IEEE.
        // (Explicit rcp14 + Newton for every division was measured mixed:
        // docs/perf-log.md.)
        llvm::FastMathFlags fmf;
        fmf.setAllowReciprocal();
        fmf.setApproxFunc();
        fmf.setAllowContract();
        builder.setFastMathFlags(fmf);
    }
}

llvm::Type* LaneEmitter::boolType() {
    if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(floatMath_.type()))
        return llvm::FixedVectorType::get(builder.getInt1Ty(), vt->getNumElements());
    return builder.getInt1Ty();
}

void LaneEmitter::markInvalid(Value* cond) { invalid_ = builder.CreateOr(invalid_, cond); }

void LaneEmitter::distrust(Value* cond) {
    if (body.guarded()) untrusted_ = builder.CreateOr(untrusted_, cond);
}

LaneEmitter::Result LaneEmitter::emit(std::array<Value*, 3> wi, std::array<Value*, 3> wo,
                                      const std::vector<Value*>& slots) {
    MathEmitter& fm = floatMath_;
    Result r;
    if (plan.wholeSphere) {
        r.rgb = wholeSphereBsdf(readDirection(wi), readDirection(wo), slots);  // LaneDielectric.cpp
    } else {
        LaneGeometry geo = geometry(readDirection(wi), readDirection(wo));
        lowerInputsAndLets(slots);
        r.rgb = brdf(geo);
    }
    // A value that overflows float is an invalid lane, never Inf/NaN, and an
    // invalid lane's value is 0. A guarded body needs neither: its invalid
    // lanes are untrusted, so their value and status come from the other
    // body, and where the plan says its guards bound the value of every
    // trusted lane (checkOutput off) no trusted lane can be NaN, Inf or
    // negative.
    if (body.checkOutput)
        markInvalid(fm.anyNanInfOrNegative({r.rgb[0], r.rgb[1], r.rgb[2]}));
    if (!body.guarded()) {
        if (fm.width() == 1) {
            zeroInvalidLaneByBranch(r.rgb);
        } else {
            for (Value*& x : r.rgb) x = fm.select(invalid_, fm.c(0.0), x);
        }
    }
    r.invalid = invalid_;
    r.untrusted = builder.CreateOr(untrusted_, invalid_);
    return r;
}

// One lane: the zeroing of an invalid lane as a branch weighted unlikely
// and a phi, not a select. A select makes the stored value wait for the
// output check at the end of the lane's longest chain; the predicted branch
// does not (the weights keep SimplifyCFG from folding it back).
void LaneEmitter::zeroInvalidLaneByBranch(std::array<Value*, 3>& values) {
    llvm::LLVMContext& ctx = builder.getContext();
    llvm::Function* fn = builder.GetInsertBlock()->getParent();
    llvm::BasicBlock* valid = builder.GetInsertBlock();
    auto* zero = llvm::BasicBlock::Create(ctx, "lane.invalid", fn);
    auto* done = llvm::BasicBlock::Create(ctx, "lane.done", fn);
    builder.CreateCondBr(invalid_, zero, done, llvm::MDBuilder(ctx).createBranchWeights(1, 1u << 20));
    builder.SetInsertPoint(zero);
    builder.CreateBr(done);
    builder.SetInsertPoint(done);
    for (Value*& x : values) {
        llvm::PHINode* phi = builder.CreatePHI(x->getType(), 2);
        phi->addIncoming(x, valid);
        phi->addIncoming(llvm::Constant::getNullValue(x->getType()), zero);
        x = phi;
    }
}

// |w|^2 in emitter `math` (double in both bodies of an exact kernel, so
// their invalid lanes agree); a non-finite or non-unit w marks the lane
// invalid. `widened` receives w in math's type. The ordered range test on
// |w|^2 is also the finiteness test: a NaN component makes |w|^2 NaN and an
// infinite one makes it +inf, and both fail it.
Value* LaneEmitter::checkedLength2(MathEmitter& math, const std::array<Value*, 3>& w, std::array<Value*, 3>& widened) {
    Value* len2 = length2(math, w, widened);
    const double lo = (1 - kUnitTolerance) * (1 - kUnitTolerance), hi = (1 + kUnitTolerance) * (1 + kUnitTolerance);
    rejectInput([&] { return math.outside(len2, lo, hi); });
    return len2;
}

Value* LaneEmitter::length2(MathEmitter& math, const std::array<Value*, 3>& w, std::array<Value*, 3>& widened) {
    for (int i = 0; i < 3; ++i) widened[i] = math.convert(w[i], math.type());
    return math.fma(widened[0], widened[0], math.fma(widened[1], widened[1], math.mul(widened[2], widened[2])));
}

// A valid direction has |w| within 1e-3 of 1, so 1/|w| = (1 + delta)^(-1/2),
// delta = |w|^2 - 1 in [-2e-3, 2e-3], is a polynomial: the binomial series
// to delta^6 leaves 0.23 delta^7 < 3e-20, below double rounding; in float
// (fast mode) the series to delta^2 leaves 0.32 delta^3 < 2.6e-9, below
// float rounding. No square root or division; lanes outside the range are
// invalid and their value unused. With a double precise type, `unitF`
// receives the unit w in float too, as w + w (1/|w| - 1) with one float FMA
// from the float input and the correction rounded to float: the same 0.5
// ulp as rounding the double unit w, for one conversion instead of three.
std::array<Value*, 3> LaneEmitter::unitDirection(const std::array<Value*, 3>& w, std::array<Value*, 3>& unitF,
                                                 Value** invLen) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    std::array<Value*, 3> out;
    Value* len2 = checkedLength2(pm, w, out);
    Value* delta = pm.sub(len2, pm.c(1.0));
    // A one-lane body waits on the double series (the first link of every
    // dependency chain): there it is evaluated by Estrin's scheme, 3
    // dependent FMAs instead of 6; a SIMD body keeps Horner's fewer
    // operations.
    Value* inv;
    if (pm.isDouble()) {
        const auto series = {1.0, -1.0 / 2, 3.0 / 8, -5.0 / 16, 35.0 / 128, -63.0 / 256, 231.0 / 1024};
        inv = pm.width() == 1 ? pm.polyEstrin(delta, series) : pm.poly(delta, series);
    } else
        inv = pm.poly(delta, {1.0, -1.0 / 2, 3.0 / 8});
    for (Value*& x : out) x = pm.mul(x, inv);
    if (invLen) *invLen = inv;
    if (pm.isDouble()) {
        Value* corr = fm.convert(pm.sub(inv, pm.c(1.0)), fm.type());
        for (int i = 0; i < 3; ++i) unitF[i] = fm.fma(w[i], corr, w[i]);
    }
    return out;
}

// 1/|w| - 1 in float for a float body, from |w|^2 - 1 taken in double
// (where the squares of floats are exact, and where the precise body
// decides the lane's validity too).
Value* LaneEmitter::unitCorrection(const std::array<Value*, 3>& w) {
    MathEmitter& fm = floatMath_;
    MathEmitter& dm = doubleMath_;
    std::array<Value*, 3> widened;
    Value* delta = fm.convert(dm.sub(length2(dm, w, widened), dm.c(1.0)), fm.type());
    // The precise body's range test on |w|^2 (checkedLength2), made on the
    // float delta: near the bounds |w|^2 - 1 is exact in double, and rounding
    // it to float is monotonic, so a delta strictly between the rounded
    // bounds is a valid lane and one outside them an invalid lane. A delta
    // equal to a rounded bound may be either: marked invalid here, the lane
    // is recomputed by the precise body, which decides. (NaN fails the
    // ordered test.) Float compares keep the lane masks in float-sized
    // lanes, where double ones make the backend pack every mask.
    // Under the host's promise the test goes, and a lane whose delta equals
    // a rounded bound stays in this body.
    const double lo = (1 - kUnitTolerance) * (1 - kUnitTolerance) - 1.0, hi = (1 + kUnitTolerance) * (1 + kUnitTolerance) - 1.0;
    rejectInput([&] {
        return builder.CreateNot(builder.CreateAnd(fm.lt(fm.c(double(float(lo))), delta), fm.lt(delta, fm.c(double(float(hi))))));
    });
    // (1 + delta)^(-1/2) - 1, the series of unitDirection() to delta^3:
    // the rest, 0.28 delta^4 <= 5e-12 for |delta| <= 2e-3, is far below
    // the float rounding of the corrected values.
    return fm.mul(delta, fm.poly(delta, {-1.0 / 2, 3.0 / 8, -5.0 / 16}));
}

// Only the difference of the two corrections ci = 1/|wi| - 1 and co needs
// to be accurate where wi + wo cancels: an error e common to both scales h
// = wi (1 + ci) + wo (1 + co) by 1 + e, which leaves its direction as it
// is, and its length (cos) and the cosines off by e relative. So the
// common part c = (ci + co)/2 comes from |w|^2 - 1 in float (three FMAs,
// off by < 6e-8 where the double |w|^2 of unitCorrection() cost a
// conversion and double arithmetic at the head of every dependency
// chain), and the difference from |wi|^2 - |wo|^2 = (wi - wo).(wi + wo),
// whose float terms are rounded relative to the sums themselves:
//   wi + wo (corrected) = (wi + wo)(1 + c) + (ci - co)/2 (wi - wo),
//   wi - wo (corrected) = (wi - wo)(1 + c) + (ci - co)/2 (wi + wo).
// Each corrected sum is then off by ~2 ulp of its length, not of each
// component (BodyPlan::floatPairCorrections says why only an isotropic NDF
// may take this). With di = |wi|^2 - 1, do likewise and s = di + do, the
// series 1/sqrt(1 + d) - 1 = -d/2 + 3d^2/8 - ... give c = -s/4 (the rest,
// < 3s^2/32, is common) and
// (ci - co)/2 = (di - do)(-1/4 + 3s/16) (the rest, < 0.12 s^2 relative).
// These hold while |di| + |do| < 1e-4 (float-rounded unit vectors are
// within 4e-7); the body distrusts the other lanes, NaN and Inf ones among
// them, and its fallback decides their validity.
LaneEmitter::CorrectedPair LaneEmitter::floatPairCorrections(const std::array<Value*, 3>& wi,
                                                              const std::array<Value*, 3>& wo) {
    MathEmitter& fm = floatMath_;
    auto lengthMinusOne = [&](const std::array<Value*, 3>& w) {
        return fm.fma(w[0], w[0], fm.fma(w[1], w[1], fm.fma(w[2], w[2], fm.c(-1.0))));
    };
    Value *di = lengthMinusOne(wi), *dO = lengthMinusOne(wo);
    distrust(builder.CreateNot(fm.lt(fm.add(fm.abs(di), fm.abs(dO)), fm.c(1e-4))));
    Value* s = fm.add(di, dO);
    CorrectedPair out;
    std::array<Value*, 3> sum, diff;
    for (int i = 0; i < 3; ++i) sum[i] = fm.add(wi[i], wo[i]), diff[i] = fm.sub(wi[i], wo[i]);
    Value* dd = fm.fma(diff[0], sum[0], fm.fma(diff[1], sum[1], fm.mul(diff[2], sum[2])));  // di - do
    Value* halfDifference = fm.mul(dd, fm.fma(s, fm.c(3.0 / 16), fm.c(-0.25)));
    Value* common = fm.mul(s, fm.c(-0.25));
    Value* onePlusCommon = fm.fma(s, fm.c(-0.25), fm.c(1.0));
    Value *ci = fm.add(common, halfDifference), *co = fm.sub(common, halfDifference);
    for (int i = 0; i < 3; ++i) {
        out.wi[i] = fm.fma(wi[i], ci, wi[i]);
        out.wo[i] = fm.fma(wo[i], co, wo[i]);
        out.sum[i] = fm.fma(sum[i], onePlusCommon, fm.mul(halfDifference, diff[i]));
        out.diff[i] = fm.fma(diff[i], onePlusCommon, fm.mul(halfDifference, sum[i]));
    }
    return out;
}

std::array<Value*, 3> LaneEmitter::readDirection(const std::array<Value*, 3>& w) {
    if (!body.subnormalCosinesAsZero) return w;
    MathEmitter& fm = floatMath_;
    return {w[0], w[1], fm.select(fm.lt(fm.abs(w[2]), fm.c(FLT_MIN)), fm.c(0.0), w[2])};
}

// SPEC 2: non-finite or non-unit directions are invalid lanes; valid ones
// are renormalized. Normalization and the half vector are computed in the
// precise type (double in exact mode): wi + wo cancels when the directions
// are nearly opposite, and the float rounding of the renormalization would
// then decide h (and so D, G and F) by itself. Float bodies (the plan's
// correctedSums) sum the float inputs and correct for the normalization.
LaneGeometry LaneEmitter::geometry(const std::array<Value*, 3>& wi, const std::array<Value*, 3>& wo, bool wiSampled) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    std::array<Value*, 3> wiD, woD;
    std::array<Value*, 3> wiF{}, woF{};  // unit directions in float, where unitDirection() made them
    std::array<Value*, 3> hD, diff;
    Value *wiInvLen = nullptr, *woInvLen = nullptr;
    if (body.floatPairCorrections && !wiSampled) {
        CorrectedPair pair = floatPairCorrections(wi, wo);
        wiD = pair.wi, woD = pair.wo, hD = pair.sum, diff = pair.diff;
    } else if (body.correctedSums) {
        // Float body. Rounding the normalized directions to float and then
        // adding them would lose h where wi + wo cancels (error eps/|wi + wo|,
        // amplified ~2/alpha by D). Instead the float inputs are summed as
        // they are (each sum rounded relative to itself) and the
        // normalization enters as a small correction w (1/|w| - 1), whose
        // own rounding is ~eps times 1e-7. |w|^2 - 1 is taken in double,
        // where the squares of floats are exact.
        // A sampled wi is the body's own unit vector (to float rounding):
        // no check and no correction.
        Value *ci = wiSampled ? nullptr : unitCorrection(wi), *co = unitCorrection(wo);
        for (int i = 0; i < 3; ++i) {
            Value* woCorr = fm.mul(wo[i], co);
            woD[i] = fm.fma(wo[i], co, wo[i]);
            wiD[i] = ci ? fm.fma(wi[i], ci, wi[i]) : wi[i];
            hD[i] = fm.add(fm.add(wi[i], wo[i]), ci ? fm.fma(wi[i], ci, woCorr) : woCorr);
            diff[i] = fm.add(fm.sub(wi[i], wo[i]), ci ? fm.fma(wi[i], ci, fm.neg(woCorr)) : fm.neg(woCorr));
        }
    } else {
        wiD = unitDirection(wi, wiF, &wiInvLen);
        woD = unitDirection(wo, woF, &woInvLen);
        hD = {pm.add(wiD[0], woD[0]), pm.add(wiD[1], woD[1]), pm.add(wiD[2], woD[2])};
        diff = {pm.sub(wiD[0], woD[0]), pm.sub(wiD[1], woD[1]), pm.sub(wiD[2], woD[2])};
    }
    const std::array<Value*, 3> hU = hD;  // wi + wo, before normalization
    Value* hlen2 = pm.fma(hD[0], hD[0], pm.fma(hD[1], hD[1], pm.mul(hD[2], hD[2])));
    // hlen, cos, 1 - cos and sin^2 are in `halfMath`: the precise type, or
    // float where the plan keeps the half angle in float.
    const bool halfInFloat = body.halfVector == HalfVectorForm::InFloat;
    MathEmitter& halfMath = halfInFloat ? fm : pm;
    Value *hlen, *cosD, *oneMinusCos;
    if (body.halfVector == HalfVectorForm::Estimated || body.halfVector == HalfVectorForm::Direct) {
        // 1 - cos = 1 - |h|/2 cancels near wi = wo, to an absolute error of
        // a few ulp of 1, which the plan allows only for Fresnel terms that
        // it cannot move visibly (none, or Schlick with a constant f0 bounded
        // below: the error of F relative to itself peaks at 4 dq/q where
        // q^5 = 4 f0). It saves the |wi - wo|^2 sum and a division.
        if (body.halfVector == HalfVectorForm::Estimated) {
            // 1/|h| as one rsqrt estimate + Newton step (the estimates flag
            // turns 1/sqrt into that), |h| = |h|^2/|h|: no square root and
            // no division; dq ~ 2e-7.
            Value* hinv = pm.div(pm.c(1.0), pm.sqrt(hlen2));
            hlen = pm.mul(hlen2, hinv);
            for (Value*& c : hD) c = pm.mul(c, hinv);
        } else {
            hlen = pm.sqrt(hlen2);
            hD = {};  // no consumer of the unit h (the plan checked)
        }
        cosD = pm.minnum(pm.mul(hlen, pm.c(0.5)), pm.c(1.0));
        oneMinusCos = pm.sub(pm.c(1.0), cosD);
    } else {
        // In float, |h|^2 >= FLT_MIN: below it (|wi + wo| < 1.1e-19) cos
        // comes out as 5.4e-20 instead of 0..5.4e-20, where the float
        // Fresnel terms use 1e-18 anyway (fresnelCos), and 1 - cos and sin^2
        // stay 1 instead of 0 * Inf.
        Value* len2 = halfInFloat ? fm.maxnum(fm.convert(hlen2, fm.type()), fm.c(FLT_MIN)) : hlen2;
        hlen = halfMath.sqrt(len2);
        // wi.h = wo.h = |wi + wo| / 2 for unit vectors: one value for both
        // keeps f exactly reciprocal. 1 - cos = |wi - wo|^2 / (2 (2 + |wi + wo|))
        // (from |wi + wo|^2 + |wi - wo|^2 = 4) has no cancellation at wi =
        // wo; |wi - wo|^2 is summed in the precise type, where wi - wo is
        // exact relative to itself.
        cosD = halfMath.minnum(halfMath.mul(hlen, halfMath.c(0.5)), halfMath.c(1.0));
        Value* diff2 =
            halfMath.convert(pm.fma(diff[0], diff[0], pm.fma(diff[1], diff[1], pm.mul(diff[2], diff[2]))), halfMath.type());
        Value* twoSum = halfMath.mul(halfMath.c(2.0), halfMath.add(halfMath.c(2.0), hlen));
        if (halfInFloat) {
            hD = {};  // no consumer of the unit h (the plan checked)
            oneMinusCos = halfMath.div(diff2, twoSum);
        } else {
            // 1/hlen and 1/(2 (2 + hlen)) from one division.
            Value* recip = halfMath.div(halfMath.c(1.0), halfMath.mul(hlen, twoSum));
            Value* hinv = pm.mul(twoSum, recip);
            for (Value*& c : hD) c = pm.mul(c, hinv);
            oneMinusCos = halfMath.mul(diff2, halfMath.mul(hlen, recip));
        }
        oneMinusCos = halfMath.minnum(oneMinusCos, halfMath.c(1.0));
    }
    // Guard: |wi + wo| >= 1e-4. h is accurate below that too, but
    // |wi + wo|^2 could underflow in float where it does not in double.
    // (On |wi + wo|^2, not on hlen: hlen = 0 * Inf = NaN is possible, and a
    // sampler whose h is the drawn normal needs no square root of it.)
    distrust(pm.lt(hlen2, pm.c(1e-8)));
    Value* sin2 = halfMath.mul(oneMinusCos, halfMath.add(halfMath.c(1.0), cosD));
    LaneGeometry g;
    g.hNonZero = pm.gt(hlen2, pm.c(0.0));
    // Rounded once to the lane type.
    for (int i = 0; i < 3; ++i) {
        g.wi[i] = wiF[i] ? wiF[i] : fm.convert(wiD[i], fm.type());
        g.wo[i] = woF[i] ? woF[i] : fm.convert(woD[i], fm.type());
        g.h[i] = hD[i] ? fm.convert(hD[i], fm.type()) : nullptr;
        g.hD[i] = hD[i] ? pm.convert(hD[i], pm.type()) : nullptr;
        g.wiD[i] = pm.convert(wiD[i], pm.type());
        g.woD[i] = pm.convert(woD[i], pm.type());
    }
    // The exponent NDFs need h only up to scale: in double they take u = wi
    // + wo itself, which the half angle in float relies on (no unit h
    // there). In float the unit h: a^2 uz^2 of near-opposite grazing
    // directions would underflow where a^2 mz^2 does not; except in the
    // float-first body where the plan leaves the unit h out (GGX's D, whose
    // lobe range guard catches that).
    if (pm.isDouble() || !hD[0]) {
        for (int i = 0; i < 3; ++i) g.slopeH[i] = pm.convert(hU[i], pm.type());
        g.slopeHLen2 = pm.convert(hlen2, pm.type());
    } else {
        g.slopeH = g.hD;
    }
    if (wiInvLen) {
        g.wiIn = wi, g.woIn = wo;
        g.wiInvLen = wiInvLen, g.woInvLen = woInvLen;
    }
    g.cosD = pm.convert(cosD, pm.type());
    g.oneMinusCosD = pm.convert(oneMinusCos, pm.type());
    g.sin2D = pm.convert(sin2, pm.type());
    return g;
}

std::array<Value*, 3> LaneEmitter::brdfPrecise(const LaneGeometry& geo, Value*& valid) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const std::array<Value*, 3>&wi = geo.wi, &wo = geo.wo;
    Value *ci = wi[2], *co = wo[2];
    // A guarded body tests the smaller cosine (one vminps, which ignores a
    // NaN cosine's order: that comes from a NaN input, whose lane the body
    // distrusts, or which the host promised not to pass).
    Value* lowerCos = body.guarded() ? fm.select(fm.lt(ci, co), ci, co) : nullptr;
    Value* above = lowerCos ? fm.gt(lowerCos, fm.c(0.0)) : b.CreateAnd(fm.gt(ci, fm.c(0.0)), fm.gt(co, fm.c(0.0)));

    // Specular lobe, F and the sum in the precise type (factors beyond
    // float range whose product is not).
    const NdfEmitter& ndf = emitters_.ndf;
    NdfParams n = ndf.params(*this);
    const bool hasSpecular = material.singleLobe().hasNdf();  // else a diffuse lobe of a combination
    Value* spec = nullptr;
    if (!hasSpecular) {
        internal_assert(!body.guarded() && !plan.compensatesEnergy) << "a diffuse lobe with a guarded body or compensation";
    } else if (ndf.traits.wholeLobe) {
        spec = ndf.wholeLobe(*this, n, geo);
    } else {
        Value* quarterD = pm.mul(ndf.D(*this, n, geo), pm.c(0.25));
        if (quarterD_.num) quarterD_.value = quarterD;
        spec = emitters_.masking.overCosines(*this, ndf, n, geo, quarterD);
    }
    const bool hasDiffuse = emitters_.diffuse.present();
    if (!hasSpecular) {
        valid = b.CreateAnd(above, geo.hNonZero);
        return (hasDiffuse ? emitters_.diffuse.diffuse(*this) : LVal::scalar(pm.c(0.0))).c;
    }
    LVal F = emitters_.fresnel.F(*this, geo);
    if (body.guarded()) {
        // Guards of a guarded body, for lanes above the horizon (the others
        // are 0 in both bodies):
        // - both cosines >= 1e-6: the Smith sums and ci co stay far from
        //   float's subnormal range;
        // - the lobe D G / (4 ci co) within [1e-20, 1e20], so D itself
        //   (>= 4e-32 given the cosines) was a normal float, and alpha^2 or
        //   the Smith projections did not overflow (they give 0);
        // - F >= 1e-8 per channel (Schlick with f0 = 0 near wi = wo
        //   underflows in float), so F times the lobe stays normal; and
        //   F <= 2 unless F <= 1 by construction (the exact terms are <= 1
        //   too, but through divisions: the bound is checked rather than
        //   argued). The plan drops the F guard where constant arguments
        //   keep F >= 1e-6 at every angle.
        // Every trusted lane's F times the lobe is then in [1e-28, 2e20]:
        // finite and positive, so without a diffuse term (whose albedo is
        // the user's expression, unbounded) the output needs no check.
        Value* bad = b.CreateOr(fm.lt(lowerCos, fm.c(1e-6)), pm.outside(spec, 1e-20, 1e20));
        for (int ch = 0; plan.fresnel.rangeGuard && ch < (F.gray() ? 1 : 3); ++ch)
            bad = b.CreateOr(bad, plan.fresnel.atMostOne ? b.CreateNot(pm.ge(F.c[ch], pm.c(1e-8)))
                                                         : pm.outside(F.c[ch], 1e-8, 2.0));
        distrust(b.CreateAnd(above, bad));
        internal_assert(!plan.compensatesEnergy) << "a guarded body with energy compensation";
    }
    LVal diffuse = hasDiffuse ? emitters_.diffuse.diffuse(*this) : LVal::scalar(pm.c(0.0));
    LVal specV = LVal::scalar(spec);
    // F = 0 (eta = 1: no interface) is 0 even where the lobe overflows (no
    // 0 * Inf). (In a guarded body such a lane is untrusted.)
    const bool zeroWhereFresnelVanishes = plan.fresnel.canVanish && !body.guarded();
    LVal total = map({F, specV, diffuse}, true, [&](auto& x) {
        Value* s = pm.mul(x[0], x[1]);
        if (zeroWhereFresnelVanishes) s = pm.select(pm.eq(x[0], pm.c(0.0)), pm.c(0.0), s);
        return hasDiffuse ? pm.add(s, x[2]) : s;
    });
    if (plan.compensatesEnergy) {
        std::array<Value*, 3> ms = emitters_.energy.compensation(*this, ndf, n, emitters_.fresnel, ci, co);
        for (int ch = 0; ch < 3; ++ch) total.c[ch] = pm.add(total.c[ch], ms[ch]);
    }
    if (plan.walksMicrosurface) {
        std::array<Value*, 3> ms = walkScattering(geo, b.CreateAnd(above, geo.hNonZero));  // LaneWalk.cpp
        for (int ch = 0; ch < 3; ++ch) total.c[ch] = pm.add(total.c[ch], ms[ch]);
    }
    // Below the horizon (or wi + wo = 0): f = 0, a valid lane. (A guarded
    // body distrusts |wi + wo|^2 < 1e-8 already.)
    valid = body.guarded() ? above : b.CreateAnd(above, geo.hNonZero);
    return total.c;
}

std::array<Value*, 3> LaneEmitter::brdf(const LaneGeometry& geo) {
    MathEmitter& fm = floatMath_;
    Value* valid = nullptr;
    LVal total{brdfPrecise(geo, valid), true};
    return map({total}, true, [&](auto& x) { return fm.select(valid, fm.convert(x[0], fm.type()), fm.c(0.0)); }).c;
}

}  // namespace facet
