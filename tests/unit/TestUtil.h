// TestUtil: small helpers shared by the front-end unit tests.
//
// Kept deliberately independent of the code under test: the S-expression
// printer below is written here (not AST.cpp's printExpr) so that a parser
// test does not pass merely because the parser and the printer agree on a
// mistake.
#pragma once

#include "AST.h"
#include "Checker.h"
#include "Diagnostics.h"
#include "Parser.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <string>
#include <vector>

namespace facet::test {

constexpr double kPi = 3.141592653589793238462643383279502884;

// (op lhs rhs), (neg x), (call f a b) with named arguments as name=value.
inline std::string sexpr(const Expr& e) {
    switch (e.kind) {
        case ExprKind::Number: return fmt::format("{}", static_cast<const NumberExpr&>(e).value);
        case ExprKind::Name: return static_cast<const NameExpr&>(e).name;
        case ExprKind::Unary: return "(neg " + sexpr(*static_cast<const UnaryExpr&>(e).operand) + ")";
        case ExprKind::Binary: {
            const auto& b = static_cast<const BinaryExpr&>(e);
            const char* op = "?";
            switch (b.op) {
                case BinaryOp::Add: op = "+"; break;
                case BinaryOp::Sub: op = "-"; break;
                case BinaryOp::Mul: op = "*"; break;
                case BinaryOp::Div: op = "/"; break;
                case BinaryOp::Pow: op = "^"; break;
            }
            return fmt::format("({} {} {})", op, sexpr(*b.lhs), sexpr(*b.rhs));
        }
        case ExprKind::Call: {
            const auto& c = static_cast<const CallExpr&>(e);
            std::string out = "(call " + c.callee;
            for (const Argument& a : c.args) out += " " + (a.name.empty() ? "" : a.name + "=") + sexpr(*a.value);
            return out + ")";
        }
    }
    return "?";
}

// All diagnostics of one engine, rendered, in the order they were reported.
inline std::vector<std::string> rendered(const DiagnosticEngine& diags) {
    std::vector<std::string> out;
    for (const Diagnostic& d : diags.diagnostics()) out.push_back(d.str());
    return out;
}

// Checks `source` (named "t.mat"); returns the rendered diagnostics.
inline std::vector<std::string> checkErrors(const std::string& source) {
    DiagnosticEngine diags;
    loadProgramText(source, "t.mat", diags);
    return rendered(diags);
}

// Wraps statements in `material m { ... }` on line 1 after "material m {\n",
// so that statement i of the body sits on line 2.
inline std::string inMaterial(const std::string& body) { return "material m {\n" + body + "\n}\n"; }

// Relative comparison for hand-computed BRDF values.
inline bool near(double a, double b, double rel = 1e-12) {
    double scale = std::max(std::abs(a), std::abs(b));
    return std::abs(a - b) <= rel * scale || (scale == 0 && a == b);
}

}  // namespace facet::test
