// ValueRange: the ranges the plan trusts to leave out a parameter's NaN and
// float-range tests. Each expression's range is checked against the values
// the expression actually takes, in double and in float, over inputs drawn
// across their ranges (bounds, zeros, extremes); a few ranges are checked
// exactly where the analysis must be tight enough to be of use.
#include "TestUtil.h"

#include "ExprEval.h"
#include "ValueRange.h"

#include <doctest/doctest.h>

#include <cfloat>
#include <random>

using namespace facet;

namespace {

// Inputs: x (no range), r in 0 .. 1, s in -2 .. 3; `let a = <expr>`.
const char* kInputs = "input x = 0.5; input r = 0.5 in 0 .. 1; input s = 0.5 in -2 .. 3;";

CheckedMaterial withLet(const std::string& expr) {
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramText(
        fmt::format("material m {{ {} let a = {}; ndf = ggx(0.3); }}", kInputs, expr), "range.mat", diags);
    INFO(diags.str());
    REQUIRE(!diags.hasErrors());
    return program.materials.at(0);
}

ValueRange rangeOf(const std::string& expr) {
    CheckedMaterial m = withLet(expr);
    return ValueRanges(m).of(*m.lets.at(0).value);
}

// The let evaluated in Real for the inputs (x, r, s), r and s clamped to
// their ranges as every evaluator clamps them.
template <typename Real>
Real evaluate(const CheckedMaterial& m, double x, double r, double s) {
    Real in[3] = {Real(x), Real(std::clamp(r, 0.0, 1.0)), Real(std::clamp(s, -2.0, 3.0))};
    auto lookup = [&](const NameExpr& n) { return Value<Real>::scalar(in[n.index]); };
    return evaluateExpr<Real>(*m.lets.at(0).value, lookup).c[0];
}

}  // namespace

TEST_SUITE("value_range") {

TEST_CASE("every value an expression takes, in double and in float, lies in its range") {
    const char* exprs[] = {
        "r * r", "r - r", "1 / r", "1 / (r + 1)", "sqrt(r - 0.5)", "sqrt(r)", "log(r)", "x * 0", "x * x",
        "(x * x) * 0", "exp(x)", "exp(s) * r", "min(r, 1 / r)", "max(s, r)", "clamp(x, 0, 1)", "clamp(s, r, 0.5)",
        "pow(r, 2.5)", "pow(s, 2.5)", "s ^ 3", "s ^ 2", "s ^ -2", "abs(s) - 3", "mix(r, s, r)", "-s / (r + 0.1)",
        "x / (s * s + 1)", "phong_exponent(r)", "beckmann_to_phong(s)", "0.1 * r + 0.2", "(r + s) * (r - s)",
        "x + x", "x - 3.4e38", "1e30 * x",
    };
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-30, -1e-30, 3.0, -2.0, FLT_MAX, -FLT_MAX, 1e20, -1e20};
    for (const char* e : exprs) {
        CAPTURE(e);
        CheckedMaterial m = withLet(e);
        ValueRange range = ValueRanges(m).of(*m.lets.at(0).value);
        CAPTURE(range.str());
        int checked = 0;
        for (int i = 0; i < 3000; ++i) {
            auto draw = [&](double lo, double hi) {
                if (i % 3 == 0) return special[(i / 3 + int(unit(rng) * 13)) % 13];
                return lo + (hi - lo) * unit(rng);
            };
            double x = i % 2 ? draw(-1e6, 1e6) : draw(-4, 4), r = draw(-0.5, 1.5), s = draw(-3, 4);
            double vd = evaluate<double>(m, x, r, s);
            float vf = evaluate<float>(m, x, r, s);
            for (double v : {vd, double(vf)}) {
                CAPTURE(x);
                CAPTURE(r);
                CAPTURE(s);
                CAPTURE(v);
                if (std::isnan(v)) {
                    CHECK(range.maybeNaN);
                } else {
                    CHECK(range.lo <= v);
                    CHECK(v <= range.hi);
                }
                ++checked;
            }
        }
        CHECK(checked == 6000);
    }
}

TEST_CASE("ranges tight enough to leave tests out") {
    ValueRange alpha = rangeOf("r * r");  // the bench materials' alpha = roughness^2
    CHECK_FALSE(alpha.maybeNaN);
    CHECK(alpha.lo == 0.0);
    CHECK(alpha.hi >= 1.0);
    CHECK(alpha.hi < 1.00001);
    CHECK(rangeOf("s * s").lo == 0.0);  // a square is never negative
    CHECK(rangeOf("s * s").hi < 9.0001);
    CHECK_FALSE(rangeOf("x * 0").maybeNaN);  // x is finite
    CHECK(rangeOf("x * x").hi == INFINITY);  // beyond float: may overflow
    CHECK_FALSE(rangeOf("x * x").maybeNaN);
    CHECK(rangeOf("(x * x) * 0").maybeNaN);  // Inf * 0
    CHECK(rangeOf("1 / r").maybeNaN);        // r may be 0
    CHECK_FALSE(rangeOf("1 / (r + 1)").maybeNaN);
    CHECK(rangeOf("1 / (r + 1)").hi < 1.00001);
    CHECK(rangeOf("sqrt(r - 0.5)").maybeNaN);
    CHECK_FALSE(rangeOf("clamp(x, 0, 1)").maybeNaN);
    CHECK(rangeOf("clamp(x, 0, 1)").hi == 1.0);
    CHECK(rangeOf("min(r, 1 / r)").maybeNaN);  // min propagates NaN
    CHECK(rangeOf("exp(x)").hi == INFINITY);
}

TEST_CASE("a parameter's range clamped to its domain; a NaN argument becomes a bound") {
    ValueRange any = ValueRange::any();
    ValueRange c = any.clampedTo(1e-4, INFINITY);
    CHECK_FALSE(c.maybeNaN);
    CHECK(c.lo == 1e-4);
    CHECK(c.hi == INFINITY);
    CHECK_FALSE(c.withinFloat());
    ValueRange nanInside = ValueRange{0.2, 0.5, true}.clampedTo(0.0, 1.0);
    CHECK(nanInside.lo == 0.2);
    CHECK(nanInside.hi == 1.0);  // minnum(NaN, 1) = 1
    ValueRange nanNoUpper = ValueRange{0.2, 0.5, true}.clampedTo(0.1, INFINITY);
    CHECK(nanNoUpper.lo == 0.1);  // maxnum(NaN, 0.1) = 0.1
    CHECK(nanNoUpper.hi == 0.5);
    CHECK(ValueRange::between(-3, 7).clampedTo(0, 1).lo == 0.0);
    CHECK(ValueRange::between(-3, 7).clampedTo(0, 1).hi == 1.0);
    CHECK(ValueRange::between(0, 3e38).withinFloat());
    CHECK_FALSE(ValueRange::between(0, 3.5e38).withinFloat());
}

}  // TEST_SUITE
