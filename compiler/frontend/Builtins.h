// Builtins: the one table of built-in functions of the language.
//
// The checker, the reference interpreter and the JIT lowering all read the
// function table, so a function is declared exactly once: its name, its
// parameters and their types, and its scalar semantics in any real type.
// Models live in the model catalog (models/ModelCatalog.h): their
// reference formulas in the entries, their IR in the entries' emitters
// (lowering/TermEmitters.h).
#pragma once

#include "AST.h"
#include "models/ModelCatalog.h"

#include <cmath>
#include <string_view>
#include <vector>

namespace facet {

// ---- functions -----------------------------------------------------------

enum class BuiltinFn {
    Rgb, Sqrt, Pow, Exp, Log, Abs, Min, Max, Clamp, Mix, PhongExponent, BeckmannToPhong,
};

struct BuiltinFunction {
    BuiltinFn id;
    const char* name;
    int arity;
    // Rgb builds an rgb from three floats; every other function works
    // channel-wise: the result type is rgb if any argument is rgb (floats are
    // promoted), float otherwise.
    bool makesRgb;
    const char* signature;  // for diagnostics, e.g. "clamp(x, lo, hi)"
    // Float operations per channel its lowering emits, weighted by what they
    // cost LLVM to compile (the checker's budget, ComputeCost.h).
    long cost;
};

const std::vector<BuiltinFunction>& builtinFunctions();
const BuiltinFunction* findBuiltinFunction(std::string_view name);

// Channel-wise semantics of a builtin (not Rgb) in any real type; args has
// `arity` values. This is the definition the interpreter uses; the JIT
// lowering implements the same formulas in IR.
template <typename Real>
Real applyBuiltin(BuiltinFn fn, const Real* a) {
    using std::abs; using std::exp; using std::log; using std::pow; using std::sqrt;
    switch (fn) {
        case BuiltinFn::Sqrt: return sqrt(a[0]);
        case BuiltinFn::Pow: return pow(a[0], a[1]);
        case BuiltinFn::Exp: return exp(a[0]);
        case BuiltinFn::Log: return log(a[0]);
        case BuiltinFn::Abs: return abs(a[0]);
        // min/max/clamp propagate NaN (a NaN parameter must invalidate the
        // lane, not be silently replaced by a bound).
        case BuiltinFn::Min: return a[0] != a[0] || a[1] != a[1] ? a[0] + a[1] : (a[1] < a[0] ? a[1] : a[0]);
        case BuiltinFn::Max: return a[0] != a[0] || a[1] != a[1] ? a[0] + a[1] : (a[1] > a[0] ? a[1] : a[0]);
        case BuiltinFn::Clamp: {
            Real lo = a[1], hi = a[2], x = a[0];
            if (x != x || lo != lo || hi != hi) return x + lo + hi;
            return x < lo ? lo : (x > hi ? hi : x);
        }
        case BuiltinFn::Mix: return a[0] + (a[1] - a[0]) * a[2];
        case BuiltinFn::PhongExponent: {  // 2/r^4 - 2 (Blinn-Phong exponent from roughness)
            Real r2 = a[0] * a[0];
            return Real(2) / (r2 * r2) - Real(2);
        }
        case BuiltinFn::BeckmannToPhong: return Real(2) / (a[0] * a[0]) - Real(2);
        case BuiltinFn::Rgb: break;
    }
    return Real(0) / Real(0);  // unreachable for checked input
}

constexpr double kUnitTolerance = 1e-3;   // SPEC 2: |len(w) - 1| allowed

}  // namespace facet
