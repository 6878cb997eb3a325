// Parser unit tests: precedence and associativity, named arguments, the
// statement forms, and syntax-error recovery with exact messages.
//
// Precedence is checked twice: structurally (an S-expression printer written
// in TestUtil.h, independent of the compiler's own printer) and by value
// (the checker folds constant input defaults, so `input a = 2^3^2;` must give
// 512, not 64). A precedence slip would silently change every material that
// writes e.g. `-x^2` or `a / b / c`.
#include "Checker.h"
#include "Parser.h"
#include "TestUtil.h"

#include <doctest/doctest.h>

#include <string>
#include <variant>

using namespace facet;
using namespace facet::test;

namespace {

// Parses `let x = EXPR;` and returns the S-expression of EXPR ("" on error).
std::string parseExpr(const std::string& expr) {
    DiagnosticEngine diags;
    Program p = parseProgram("material m { let x = " + expr + "; ndf = ggx(1); }", "t.mat", diags);
    if (diags.hasErrors() || p.materials.size() != 1) return "<error: " + diags.str() + ">";
    const Stmt& s = p.materials[0].statements.at(0);
    const LetDecl* let = std::get_if<LetDecl>(&s);
    return let ? sexpr(*let->value) : "<not a let>";
}

// The constant an input default folds to (via the checker's evaluator).
double foldConstant(const std::string& expr) {
    DiagnosticEngine diags;
    CheckedProgram prog = loadProgramText("material m { input a = " + expr + "; ndf = ggx(1); }", "t.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    return prog.materials.at(0).inputs.at(0).defaultValue[0];
}

const ModelStmt& modelStmt(const Program& p, size_t i) { return std::get<ModelStmt>(p.materials.at(0).statements.at(i)); }

}  // namespace

TEST_SUITE("parser") {

TEST_CASE("unary minus binds looser than ^: -x^2 = -(x^2)") {
    CHECK(parseExpr("-x^2") == "(neg (^ x 2))");
    CHECK(foldConstant("-3^2") == -9);
    CHECK(foldConstant("(-3)^2") == 9);
    // ...but tighter than * and +.
    CHECK(parseExpr("-a*b") == "(* (neg a) b)");
    CHECK(parseExpr("a - -b") == "(- a (neg b))");
}

TEST_CASE("^ is right-associative: 2^3^2 = 2^9") {
    CHECK(parseExpr("2^3^2") == "(^ 2 (^ 3 2))");
    CHECK(foldConstant("2^3^2") == 512);
    // The exponent may itself be negated: 2^-1 = 0.5, 2^-2^2 = 2^-(2^2).
    CHECK(parseExpr("2^-1") == "(^ 2 (neg 1))");
    CHECK(foldConstant("2^-1") == 0.5);
    CHECK(foldConstant("2^-2^2") == 1.0 / 16);
}

TEST_CASE("- and / are left-associative") {
    CHECK(parseExpr("8-4-2") == "(- (- 8 4) 2)");
    CHECK(foldConstant("8-4-2") == 2);
    CHECK(parseExpr("8/4/2") == "(/ (/ 8 4) 2)");
    CHECK(foldConstant("8/4/2") == 1);
    CHECK(foldConstant("1-2+3") == 2);
    CHECK(foldConstant("12/3*2") == 8);
}

TEST_CASE("* and / bind tighter than + and -; parentheses override") {
    CHECK(parseExpr("1+2*3") == "(+ 1 (* 2 3))");
    CHECK(foldConstant("2*3+4*5") == 26);
    CHECK(parseExpr("(1+2)*3") == "(* (+ 1 2) 3)");
    CHECK(foldConstant("(1+2)*3") == 9);
    CHECK(parseExpr("a*b^c") == "(* a (^ b c))");
}

TEST_CASE("calls: positional and named arguments, nesting") {
    CHECK(parseExpr("clamp(x, 0, 1)") == "(call clamp x 0 1)");
    CHECK(parseExpr("rgb(1, 2 * a, -3)") == "(call rgb 1 (* 2 a) (neg 3))");
    CHECK(parseExpr("mix(a, sqrt(b), 0.5)^2") == "(^ (call mix a (call sqrt b) 0.5) 2)");
    CHECK(parseExpr("f()") == "(call f)");
}

TEST_CASE("model statements keep argument names and their locations") {
    DiagnosticEngine diags;
    Program p = parseProgram(
        "material m {\n"
        "  ndf = ggx(alpha_x = 0.1, alpha_y = 2 * 0.1);\n"
        "  masking = smith_height_correlated;\n"
        "  fresnel = schlick(0.04);\n"
        "}\n",
        "t.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    const ModelStmt& ndf = modelStmt(p, 0);
    CHECK(ndf.slot == ModelSlot::Ndf);
    CHECK(ndf.model == "ggx");
    CHECK(ndf.loc.line == 2);
    CHECK(ndf.loc.col == 3);
    CHECK(ndf.modelLoc.col == 9);
    REQUIRE(ndf.args.size() == 2);
    CHECK(ndf.args[0].name == "alpha_x");
    CHECK(ndf.args[0].nameLoc.col == 13);
    CHECK(sexpr(*ndf.args[0].value) == "0.1");
    CHECK(ndf.args[1].name == "alpha_y");
    CHECK(sexpr(*ndf.args[1].value) == "(* 2 0.1)");
    const ModelStmt& masking = modelStmt(p, 1);
    CHECK(masking.slot == ModelSlot::Masking);
    CHECK(masking.model == "smith_height_correlated");
    CHECK(masking.args.empty());
    const ModelStmt& fresnel = modelStmt(p, 2);
    REQUIRE(fresnel.args.size() == 1);
    CHECK(fresnel.args[0].name.empty());
}

TEST_CASE("inputs with and without ranges, lets, several materials") {
    DiagnosticEngine diags;
    Program p = parseProgram(
        "material a { input r = 0.5 in 0 .. 1; input t = rgb(1, 1, 1); let k = r * 2; ndf = ggx(k); }\n"
        "material b { ndf = beckmann(0.2); }\n",
        "t.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    REQUIRE(p.materials.size() == 2);
    CHECK(p.materials[0].name == "a");
    CHECK(p.materials[1].name == "b");
    CHECK(p.materials[1].loc.line == 2);
    CHECK(p.materials[1].loc.col == 10);
    const auto& r = std::get<InputDecl>(p.materials[0].statements[0]);
    CHECK(r.name == "r");
    REQUIRE(r.lo);
    REQUIRE(r.hi);
    CHECK(sexpr(*r.lo) == "0");
    CHECK(sexpr(*r.hi) == "1");
    const auto& t = std::get<InputDecl>(p.materials[0].statements[1]);
    CHECK(!t.lo);
    CHECK(!t.hi);
    CHECK(sexpr(*t.defaultValue) == "(call rgb 1 1 1)");
    CHECK(std::get<LetDecl>(p.materials[0].statements[2]).name == "k");
}

TEST_CASE("syntax errors: exact message and location, recovery at ';'") {
    DiagnosticEngine diags;
    Program p = parseProgram(
        "material m {\n"
        "  let a = 1 +;\n"           // expression missing
        "  let b = 2\n"              // ';' missing: reported at the next token
        "  ndf = ggx(0.1);\n"
        "  masking none;\n"          // '=' missing
        "}\n",
        "t.mat", diags);
    CHECK(rendered(diags) == std::vector<std::string>{
                                 "t.mat:2:14: error: expected an expression, found ';'",
                                 "t.mat:4:3: error: expected ';' after the let statement, found 'ndf'",
                                 "t.mat:5:11: error: expected '=' after 'masking', found 'none'",
                             });
    // The material lost statements, so it is marked and the checker skips it.
    REQUIRE(p.materials.size() == 1);
    CHECK(p.materials[0].hasSyntaxErrors);
}

TEST_CASE("missing '}' and stray top-level tokens") {
    CHECK(checkErrors("material m { ndf = ggx(1);\n") ==
          std::vector<std::string>{"t.mat:2:1: error: missing '}' to close material 'm'"});
    CHECK(checkErrors("material m { ndf = ggx(1);\nmaterial n { ndf = ggx(1); }") ==
          std::vector<std::string>{"t.mat:2:1: error: missing '}' to close material 'm'"});
    CHECK(checkErrors("ndf = ggx(1);") == std::vector<std::string>{"t.mat:1:1: error: expected 'material', found 'ndf'"});
    CHECK(checkErrors("") ==
          std::vector<std::string>{"t.mat:1:1: error: file contains no material (expected 'material NAME { ... }')"});
}

TEST_CASE("numbers too large for a double are reported where they stand") {
    CHECK(checkErrors("material m { ndf = ggx(1e999); }") ==
          std::vector<std::string>{"t.mat:1:24: error: number '1e999' is too large"});
    // Underflow is not an error: 1e-400 is 0 (and the NDF clamps alpha).
    CHECK(foldConstant("1e-400") == 0);
}

TEST_CASE("nesting is bounded so that no input exhausts the stack") {
    std::string ok = std::string(150, '(') + "1" + std::string(150, ')');
    CHECK(foldConstant(ok) == 1);
    std::string deep = std::string(10000, '(') + "1" + std::string(10000, ')');
    auto errors = checkErrors("material m { let a = " + deep + "; ndf = ggx(1); }");
    REQUIRE(errors.size() == 1);
    CHECK(errors[0].find("error: expression nested too deeply (more than 200 levels)") != std::string::npos);
    // The same for unary minus and for the right-recursive '^'.
    CHECK(checkErrors("material m { let a = " + std::string(10000, '-') + "1; ndf = ggx(1); }").size() == 1);
    std::string pow;
    for (int i = 0; i < 10000; ++i) pow += "2^";
    CHECK(checkErrors("material m { let a = " + pow + "2; ndf = ggx(1); }").size() == 1);
}

}  // TEST_SUITE
