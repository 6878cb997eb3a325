// Vector math accuracy: each MathEmitter function is JIT-compiled as a
// 16-lane and a scalar kernel over float, swept over its domain, and
// compared with long double libm. The bounds asserted here are the ones
// VectorMath.h states.
#include "Jit.h"
#include "NewtonLoop.h"
#include "VectorMath.h"

#include <doctest/doctest.h>
#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <functional>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/Module.h>
#include <random>

using namespace facet;
using llvm::Value;

namespace {

using Emit = std::function<Value*(MathEmitter&, Value*, Value*)>;
using ArrayFn = void (*)(const float*, const float*, float*, int64_t);
using DoubleArrayFn = void (*)(const double*, const double*, double*, int64_t);

// Builds void f(const float* x, const float* y, float* out, i64 n) that
// applies `emit` 16 lanes at a time (vector) or one at a time (scalar),
// with the exact or the fast (shorter polynomials) emitter; over doubles
// instead of floats with `inDouble` (a DoubleArrayFn).
ArrayFn build(FacetJit& jit, const Emit& emit, bool vector, std::vector<llvm::orc::JITDylib*>& keep, bool fast,
              bool inDouble = false) {
    llvm::LLVMContext ctx;
    auto module = std::make_unique<llvm::Module>("math", ctx);
    llvm::IRBuilder<> b(ctx);
    llvm::Type* ptr = b.getPtrTy();
    auto* fnTy = llvm::FunctionType::get(b.getVoidTy(), {ptr, ptr, ptr, b.getInt64Ty()}, false);
    auto* fn = llvm::Function::Create(fnTy, llvm::Function::ExternalLinkage, "apply", *module);
    const int W = vector ? 16 : 1;
    llvm::Type* elem = inDouble ? b.getDoubleTy() : b.getFloatTy();
    llvm::Type* ty = vector ? (llvm::Type*)llvm::FixedVectorType::get(elem, W) : elem;
    const llvm::Align align(inDouble ? 8 : 4);
    auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
    auto* loop = llvm::BasicBlock::Create(ctx, "loop", fn);
    auto* done = llvm::BasicBlock::Create(ctx, "done", fn);
    b.SetInsertPoint(entry);
    b.CreateBr(loop);
    b.SetInsertPoint(loop);
    llvm::PHINode* i = b.CreatePHI(b.getInt64Ty(), 2);
    i->addIncoming(b.getInt64(0), entry);
    Value* x = b.CreateAlignedLoad(ty, b.CreateGEP(elem, fn->getArg(0), i), align);
    Value* y = b.CreateAlignedLoad(ty, b.CreateGEP(elem, fn->getArg(1), i), align);
    MathEmitter m(b, ty, fast);
    b.CreateAlignedStore(emit(m, x, y), b.CreateGEP(elem, fn->getArg(2), i), align);
    Value* next = b.CreateAdd(i, b.getInt64(W));
    i->addIncoming(next, b.GetInsertBlock());  // `emit` may have branched (gaussianQuantile)
    b.CreateCondBr(b.CreateICmpSLT(next, fn->getArg(3)), loop, done);
    b.SetInsertPoint(done);
    b.CreateRetVoid();
    jit.optimize(*module);
    llvm::orc::JITDylib& dylib = jit.addObject(jit.emitObject(*module));
    keep.push_back(&dylib);
    return reinterpret_cast<ArrayFn>(jit.lookup(dylib, "apply"));
}

double ulpError(float got, long double want) {
    if (std::isnan(got) && std::isnan(double(want))) return 0;
    if (std::isinf(got) && std::isinf(float(want)) && (got > 0) == (want > 0)) return 0;
    float w = float(want);
    float ulp = std::nextafter(std::fabs(w), INFINITY) - std::fabs(w);
    if (ulp == 0 || !std::isfinite(ulp)) ulp = std::numeric_limits<float>::denorm_min();
    return double(std::fabs((long double)got - want) / ulp);
}

struct Sweep {
    std::vector<float> x, y;
};

// Log-spaced and uniform points over [lo, hi], both signs when asked.
Sweep sweep(double lo, double hi, double ylo = 0, double yhi = 0, size_t n = 1 << 16) {
    Sweep s;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (size_t i = 0; i < n; ++i) {
        double t = double(i) / double(n - 1);
        double v = (lo > 0 && i % 2) ? std::exp(std::log(lo) + t * (std::log(hi) - std::log(lo))) : lo + (hi - lo) * u(rng);
        s.x.push_back(float(v));
        s.y.push_back(float(ylo + (yhi - ylo) * u(rng)));
    }
    return s;
}

// `emit` applied to the sweep by the kernel build() makes.
std::vector<float> run(FacetJit& jit, const Emit& emit, const Sweep& s, bool vector,
                       std::vector<llvm::orc::JITDylib*>& keep, bool fast) {
    ArrayFn f = build(jit, emit, vector, keep, fast);
    std::vector<float> out(s.x.size());
    f(s.x.data(), s.y.data(), out.data(), int64_t(s.x.size()));
    return out;
}

// A double emitter of x's shape (one value or 16 lanes), for checking double
// paths through the float harness.
MathEmitter doubleEmitter(MathEmitter& m, Value* x, bool fast) {
    llvm::Type* dt = x->getType()->isVectorTy() ? (llvm::Type*)llvm::FixedVectorType::get(m.b.getDoubleTy(), 16)
                                                : m.b.getDoubleTy();
    return MathEmitter(m.b, dt, fast);
}

double maxUlp(FacetJit& jit, const Emit& emit, const Sweep& s, const std::function<long double(long double, long double)>& ref,
              std::vector<llvm::orc::JITDylib*>& keep, double* maxRel = nullptr, bool fast = false) {
    double worst = 0;
    for (bool vector : {false, true}) {
        std::vector<float> out = run(jit, emit, s, vector, keep, fast);
        for (size_t i = 0; i < s.x.size(); ++i) {
            long double want = ref(s.x[i], s.y[i]);
            worst = std::max(worst, ulpError(out[i], want));
            if (maxRel && std::isfinite(double(want)) && want != 0)
                *maxRel = std::max(*maxRel, double(std::fabs((out[i] - want) / want)));
        }
    }
    return worst;
}

}  // namespace

TEST_CASE("vector math accuracy in float, scalar and 16 lanes") {
    auto jit = FacetJit::Create();
    std::vector<llvm::orc::JITDylib*> keep;
    double u;
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.exp(x); }, sweep(-103, 88.7),
               [](long double x, long double) { return std::exp(x); }, keep);
    MESSAGE("exp max ulp " << u);
    CHECK(u <= 1.0);
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.log(x); }, sweep(1e-44, 3e38),
               [](long double x, long double) { return std::log(x); }, keep);
    MESSAGE("log max ulp " << u);
    CHECK(u <= 1.0);
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.log1p(x); }, sweep(-0.999, 1e6),
               [](long double x, long double) { return std::log1p(x); }, keep);
    MESSAGE("log1p max ulp " << u);
    CHECK(u <= 2.0);
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value* y) { return m.pow(x, y); }, sweep(1e-3, 1e3, -10, 10),
               [](long double x, long double y) { return std::pow(x, y); }, keep);
    MESSAGE("pow max ulp " << u);
    CHECK(u <= 1.0);
    double rel = 0;
    maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.erfcx(x); }, sweep(0, 4.0),
           [](long double x, long double) { return std::exp(x * x) * std::erfc(x); }, keep, &rel);
    MESSAGE("erfcx max relative error " << rel);
    CHECK(rel <= 3e-7);
    double relFast = 0;  // fast mode's degree-7 fit (1.5e-7) plus rounding
    maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.erfcx(x); }, sweep(0, 4.0),
           [](long double x, long double) { return std::exp(x * x) * std::erfc(x); }, keep, &relFast, /*fast=*/true);
    MESSAGE("erfcx (fast) max relative error " << relFast);
    CHECK(relFast <= 4e-7);
    // erfcxWide in double over [0, 8] against long double
    // (exp(x^2) erfc(x) from erfcl: its rounding, ~1e-19, is far below the bound).
    {
        std::vector<double> x, y, out;
        for (int i = 0; i < 1 << 14; ++i) x.push_back(8.0 * i / ((1 << 14) - 1)), y.push_back(0);
        double worst = 0;
        for (bool vector : {false, true}) {
            auto f = reinterpret_cast<DoubleArrayFn>(
                build(*jit, [](MathEmitter& m, Value* v, Value*) { return m.erfcxWide(v); }, vector, keep, false, true));
            out.assign(x.size(), -1);
            f(x.data(), y.data(), out.data(), int64_t(x.size()));
            for (size_t i = 0; i < x.size(); ++i) {
                long double X = x[i], want = std::exp(X * X) * std::erfc(X);
                worst = std::max(worst, double(std::fabs((out[i] - want) / want)));
            }
        }
        MESSAGE("erfcxWide (double) max relative error " << worst);
        CHECK(worst <= 4e-15);
    }
    // gaussianQuantile in double: y with erfc(-y)/2 = u against a long double
    // bisection on erfcl (from the lower tail by symmetry, where 1 - u is
    // exact), u uniform on (0, 1), log-spaced down to 1e-30 and as close to 1
    // as a float u gets; beyond the limit 8 (u below erfc(8)/2 = 5.6e-30,
    // and u = 0 or 1) the clamped value. The lanes of one vector mix fitted
    // and far-tail starts (u below 2.8e-8, which take a second step in a
    // branch): the scalar and vector functions must agree bit for bit (a
    // lane's value does not depend on whether a neighbour took the branch).
    {
        auto reference = [](long double u) {
            bool upper = u > 0.5L;
            long double q = upper ? 1 - u : u, lo = -9, hi = 0;
            for (int i = 0; i < 200; ++i) {
                long double mid = (lo + hi) / 2;
                (std::erfc(-mid) / 2 < q ? lo : hi) = mid;
            }
            long double y = std::clamp((lo + hi) / 2, -8.0L, 0.0L);
            return upper ? -y : y;
        };
        std::vector<double> x, y, out;
        std::mt19937_64 rng(9);
        std::uniform_real_distribution<double> uniform(0, 1);
        for (int i = 0; i < 4096; ++i) {
            double tail = std::pow(10.0, -7 - 23.0 * i / 4095);
            for (double v : {uniform(rng), tail, 1 - std::max(tail, 0x1p-24)}) x.push_back(v), y.push_back(0);
        }
        for (double v : {0.0, 1.0, 1e-35, 0.5, 0x1p-24, 1 - 0x1p-24, 2.9e-8, 2.7e-8}) x.push_back(v), y.push_back(0);
        while (x.size() % 16) x.push_back(0.25), y.push_back(0);
        std::vector<long double> want;
        for (double v : x) want.push_back(reference(v));
        double worst = 0;
        std::vector<double> scalarOut;
        for (bool vector : {false, true}) {
            auto f = reinterpret_cast<DoubleArrayFn>(build(
                *jit, [](MathEmitter& m, Value* v, Value*) { return m.gaussianQuantile(v, 8.0); }, vector, keep, false,
                true));
            out.assign(x.size(), NAN);
            f(x.data(), y.data(), out.data(), int64_t(x.size()));
            for (size_t i = 0; i < x.size(); ++i) {
                double err = double(std::fabs(out[i] - want[i]));
                INFO("u = " << x[i] << ": " << out[i] << ", want " << double(want[i]));
                CHECK(err <= 1e-14);
                worst = std::max(worst, err);
            }
            if (!vector) scalarOut = out;
        }
        for (size_t i = 0; i < x.size(); ++i) CHECK(std::bit_cast<uint64_t>(out[i]) == std::bit_cast<uint64_t>(scalarOut[i]));
        MESSAGE("gaussianQuantile (double) max absolute error " << worst);
    }
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value* y) { return m.atan2(m.abs(y), x); }, sweep(-10, 10, -10, 10),
               [](long double x, long double y) { return std::atan2(std::fabs(y), x); }, keep);
    MESSAGE("atan2 max ulp " << u);
    CHECK(u <= 3.0);
    // expNormal: exp without its range handling, for arguments the caller
    // bounded to [-85, 85] (float) or [-700, 700] (double). Its values must
    // be exp()'s bit for bit there: in float directly, and in double as
    // expNormal(X) / exp(X) == 1 with X = x * 700/85 (a double result would
    // not fit the float output).
    for (bool fast : {false, true}) {
        u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.sub(m.expNormal(x), m.exp(x)); },
                   sweep(-85, 85), [](long double, long double) { return 0.0L; }, keep, nullptr, fast);
        CHECK(u == 0.0);
        u = maxUlp(
            *jit,
            [fast](MathEmitter& m, Value* x, Value*) {
                MathEmitter d = doubleEmitter(m, x, fast);
                Value* X = d.mul(d.convert(x, d.type()), d.c(700.0 / 85.0));
                return m.convert(d.div(d.expNormal(X), d.exp(X)), m.type());
            },
            sweep(-85, 85), [](long double, long double) { return 1.0L; }, keep, nullptr, fast);
        CHECK(u == 0.0);
    }
    // expNormal(x, floatResult) in double: the series to r^9, within ~1e-11
    // of exp (printed and checked as (ratio - 1) * 1e10, within 0.1).
    {
        Emit emit = [](MathEmitter& m, Value* x, Value*) {
            MathEmitter d = doubleEmitter(m, x, false);
            Value* X = d.mul(d.convert(x, d.type()), d.c(700.0 / 85.0));
            Value* ratio = d.div(d.expNormal(X, /*floatResult=*/true), d.exp(X));
            return m.convert(d.mul(d.sub(ratio, d.c(1.0)), d.c(1e10)), m.type());
        };
        Sweep s = sweep(-85, 85);
        double worst = 0;
        for (bool vector : {false, true})
            for (float v : run(*jit, emit, s, vector, keep, false)) worst = std::max(worst, double(std::fabs(v)) * 1e-10);
        MESSAGE("expNormal (float result, double) max relative difference from exp " << worst);
        CHECK(worst <= 2e-11);  // measured 9.4e-12
    }
    // Special values.
    Sweep special;
    special.x = {0.0f, -0.0f, INFINITY, -INFINITY, NAN, 1e-45f, -1.0f, 89.0f, -104.0f};
    special.y = special.x;
    for (int k = 0; k < 7; ++k) special.x.push_back(1.0f), special.y.push_back(0.0f);  // pad to 16
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.exp(x); }, special,
               [](long double x, long double) { return std::exp(x); }, keep);
    CHECK(u <= 1.0);  // 0, inf, nan, overflow and underflow exact; the padding 1.0 rounds
    u = maxUlp(*jit, [](MathEmitter& m, Value* x, Value*) { return m.log(x); }, special,
               [](long double x, long double) { return std::log(x); }, keep);
    CHECK(u <= 1.0);
    for (auto* d : keep) jit->release(*d);
}

// outside(x, lo, hi) tests bits on vectors (one unsigned compare) and
// ordered compares on one lane: both must say what not (lo <= x <= hi)
// says, for float and double lanes, at the bounds and their neighbours,
// for 0 and -0, negatives, subnormals, infinities and NaN of either sign.
// emitBracketedNewton (NewtonLoop.h): the cube root of a, Newton's and
// Halley's steps from a start that is good for some lanes and poor for
// others, with a loose settling step (2^-9, floor 1), so that lanes settle
// after different step counts within one vector. Each lane keeps the value
// of the step that settled it: the 16-lane function gives every lane the
// bits the one-lane function gives it, and a lane whose neighbours need
// more steps is not moved by them. Also: the roots within the error the
// settling step allows, and a lane whose start lies outside the bracket (a
// = 900, start 900) reaches the root by bisecting first.
TEST_CASE("bracketed Newton: each lane keeps the step that settled it, whatever its neighbours") {
    auto jit = FacetJit::Create();
    std::vector<llvm::orc::JITDylib*> keep;
    std::vector<double> a, unused;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uniform(0.5, 2.0);
    for (int i = 0; i < 256; ++i) a.push_back(i % 5 == 0 ? 900.0 * uniform(rng) / 2 : uniform(rng));
    unused.assign(a.size(), 0);
    for (bool halley : {false, true}) {
        std::vector<double> outs[2];
        for (bool vector : {false, true}) {
            Emit emit = [halley](MathEmitter& m, Value* x, Value*) {
                auto eval = [&](Value* v) {
                    NewtonTerms t{m.sub(m.mul(m.mul(v, v), v), x), m.mul(m.c(3.0), m.mul(v, v))};
                    if (halley) t.curvature = m.mul(m.c(6.0), v);
                    return t;
                };
                return emitBracketedNewton(m.b, m, eval, x, m.c(0.0), m.c(10.0), 40, 0x1p-9, 1.0);
            };
            auto f = reinterpret_cast<DoubleArrayFn>(build(*jit, emit, vector, keep, false, true));
            outs[vector].assign(a.size(), NAN);
            f(a.data(), unused.data(), outs[vector].data(), int64_t(a.size()));
        }
        for (size_t i = 0; i < a.size(); ++i) {
            INFO("halley " << halley << " a = " << a[i] << ": one lane " << outs[0][i] << ", in a vector "
                           << outs[1][i]);
            CHECK(std::bit_cast<uint64_t>(outs[0][i]) == std::bit_cast<uint64_t>(outs[1][i]));
            CHECK(std::fabs(outs[1][i] - std::cbrt(a[i])) <= 1e-4 * std::cbrt(a[i]));
        }
    }
}

TEST_CASE("outside(x, lo, hi) is not (lo <= x <= hi) on every kind of value") {
    auto jit = FacetJit::Create();
    std::vector<llvm::orc::JITDylib*> keep;
    for (auto [lo, hi] : {std::pair{1e-20, 1e20}, std::pair{1e-8, 2.0}}) {
        const float flo = float(lo), fhi = float(hi);
        Sweep s;
        s.x = {0.0f, -0.0f, flo, fhi, std::nextafter(flo, 0.0f), std::nextafter(flo, 1.0f), std::nextafter(fhi, 0.0f),
               std::nextafter(fhi, INFINITY), -flo, -fhi, 1e-45f, -1e-45f, INFINITY, -INFINITY, NAN, -NAN, 1.0f, 0.5f,
               3.0f, FLT_MAX, -FLT_MAX, 1e-30f, 1e30f};
        while (s.x.size() % 16) s.x.push_back(1.0f);
        s.y = s.x;
        for (bool inDouble : {false, true}) {
            Emit emit = [lo, hi, inDouble](MathEmitter& m, Value* x, Value*) {
                if (!inDouble) return m.select(m.outside(x, lo, hi), m.c(1.0), m.c(0.0));
                MathEmitter d = doubleEmitter(m, x, false);
                return m.select(d.outside(d.convert(x, d.type()), lo, hi), m.c(1.0), m.c(0.0));
            };
            for (bool vector : {false, true}) {
                std::vector<float> out = run(*jit, emit, s, vector, keep, false);
                for (size_t i = 0; i < s.x.size(); ++i) {
                    const double x = s.x[i];
                    const bool inside = inDouble ? (lo <= x && x <= hi) : (flo <= s.x[i] && s.x[i] <= fhi);
                    INFO("x = " << x << ", [" << lo << ", " << hi << "], " << (inDouble ? "double" : "float")
                                << (vector ? ", 16 lanes" : ", one lane"));
                    CHECK(out[i] == (inside ? 0.0f : 1.0f));
                }
            }
        }
    }
    for (auto* d : keep) jit->release(*d);
}
