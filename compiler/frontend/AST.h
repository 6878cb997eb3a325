// AST: the parsed material language, as plain node structs.
//
// Expressions are immutable-after-checking trees shared by pointer. The
// checker annotates each expression with its type and resolves names and
// calls in place; passes after checking (specialization, lowering) build new
// trees with ExprMutator rather than editing shared ones. Every node carries
// the file:line:col it was parsed from.
#pragma once

#include "SourceLoc.h"

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace facet {

enum class ValueType { Unknown, Float, Rgb };
const char* valueTypeName(ValueType t);

struct BuiltinFunction;  // Builtins.h

enum class ExprKind { Number, Name, Unary, Binary, Call };
enum class BinaryOp { Add, Sub, Mul, Div, Pow };
const char* binaryOpSpelling(BinaryOp op);

struct Expr;
using ExprPtr = std::shared_ptr<Expr>;

struct Expr {
    ExprKind kind;
    SourceLoc loc;
    ValueType type = ValueType::Unknown;  // set by the checker
    int depth = 1;  // height of this subtree; the parser bounds it so that no pass can overflow the stack
    explicit Expr(ExprKind k, SourceLoc l) : kind(k), loc(std::move(l)) {}
    virtual ~Expr() = default;
};

struct NumberExpr : Expr {
    double value;
    NumberExpr(SourceLoc l, double v) : Expr(ExprKind::Number, std::move(l)), value(v) {}
};

// What a name refers to once the checker has resolved it.
enum class BindingKind { Unresolved, Input, Let };
struct NameExpr : Expr {
    std::string name;
    BindingKind binding = BindingKind::Unresolved;
    int index = -1;  // into CheckedMaterial::inputs or ::lets
    NameExpr(SourceLoc l, std::string n) : Expr(ExprKind::Name, std::move(l)), name(std::move(n)) {}
};

struct UnaryExpr : Expr {  // only negation exists
    ExprPtr operand;
    UnaryExpr(SourceLoc l, ExprPtr e) : Expr(ExprKind::Unary, std::move(l)), operand(std::move(e)) {}
};

struct BinaryExpr : Expr {
    BinaryOp op;
    ExprPtr lhs, rhs;
    BinaryExpr(SourceLoc l, BinaryOp o, ExprPtr a, ExprPtr b)
        : Expr(ExprKind::Binary, std::move(l)), op(o), lhs(std::move(a)), rhs(std::move(b)) {}
};

// An argument of a call or model use: positional (name empty) or named.
struct Argument {
    std::string name;
    SourceLoc nameLoc;
    ExprPtr value;
};

struct CallExpr : Expr {
    std::string callee;
    std::vector<Argument> args;
    const BuiltinFunction* function = nullptr;  // set by the checker
    CallExpr(SourceLoc l, std::string c, std::vector<Argument> a)
        : Expr(ExprKind::Call, std::move(l)), callee(std::move(c)), args(std::move(a)) {}
};

// ---- statements ----------------------------------------------------------

struct InputDecl {
    SourceLoc loc;  // of the name
    std::string name;
    ExprPtr defaultValue;
    ExprPtr lo, hi;  // both null when there is no range
};

struct LetDecl {
    SourceLoc loc;
    std::string name;
    ExprPtr value;
};

// The five model slots of a material.
enum class ModelSlot { Ndf, Masking, Fresnel, Energy, Diffuse };
constexpr int kModelSlotCount = 5;
const char* modelSlotName(ModelSlot slot);

// `slot = model(args);`
struct ModelStmt {
    SourceLoc loc;  // of the slot keyword
    ModelSlot slot;
    SourceLoc modelLoc;
    std::string model;
    std::vector<Argument> args;
};

// `scatter = both;`, `thin = true;` (SPEC 11): how a lobe scatters, a word
// after the option's name. The checker knows the options and their words.
struct LobeOptionStmt {
    SourceLoc loc;  // of the option's name
    std::string option;
    SourceLoc valueLoc;
    std::string value;
};
// The options a lobe statement may set (the parser tells them from model
// statements by these names).
bool isLobeOption(const std::string& name);

// `lobe NAME { slot = model(args); ... }` (SPEC 10): the model statements and
// options of one lobe. Inputs and lets stay at material level.
struct LobeDecl {
    SourceLoc loc;  // of the name
    std::string name;
    std::vector<ModelStmt> statements;
    std::vector<LobeOptionStmt> options;
};

// `bsdf = EXPR;`: how the lobes combine. The expression is parsed with the
// ordinary expression grammar (lobe names are names, `mix` and `layer` are
// calls, weights are products); the checker tells lobes from numbers.
struct BsdfStmt {
    SourceLoc loc;  // of the `bsdf` keyword
    ExprPtr value;
};

using Stmt = std::variant<InputDecl, LetDecl, ModelStmt, LobeOptionStmt, LobeDecl, BsdfStmt>;

struct MaterialDecl {
    SourceLoc loc;  // of the name
    std::string name;
    std::vector<Stmt> statements;
    bool hasSyntaxErrors = false;  // some statements were dropped; do not check it
};

struct Program {
    std::shared_ptr<const std::string> file;
    std::vector<MaterialDecl> materials;
};

// ---- traversal -----------------------------------------------------------

// Visits an expression tree; every visit method recurses into children by
// default, so a pass overrides only the nodes it cares about.
class ExprVisitor {
public:
    virtual ~ExprVisitor() = default;
    void visit(const Expr& e);
    virtual void visitNumber(const NumberExpr&) {}
    virtual void visitName(const NameExpr&) {}
    virtual void visitUnary(const UnaryExpr& e) { visit(*e.operand); }
    virtual void visitBinary(const BinaryExpr& e) {
        visit(*e.lhs);
        visit(*e.rhs);
    }
    virtual void visitCall(const CallExpr& e) {
        for (const Argument& a : e.args) visit(*a.value);
    }
};

// Rebuilds an expression tree; by default a node is returned unchanged when
// none of its children changed, and copied with the new children otherwise.
class ExprMutator {
public:
    virtual ~ExprMutator() = default;
    ExprPtr mutate(const ExprPtr& e);
    virtual ExprPtr mutateNumber(const std::shared_ptr<NumberExpr>& e) { return e; }
    virtual ExprPtr mutateName(const std::shared_ptr<NameExpr>& e) { return e; }
    virtual ExprPtr mutateUnary(const std::shared_ptr<UnaryExpr>& e);
    virtual ExprPtr mutateBinary(const std::shared_ptr<BinaryExpr>& e);
    virtual ExprPtr mutateCall(const std::shared_ptr<CallExpr>& e);
};

// Prints an expression in source syntax (fully parenthesized binary ops).
std::string printExpr(const Expr& e);

// The value of an integer-valued number literal with |k| <= 64: pow with
// such an exponent is lowered as repeated multiplication, and the value
// ranges (ValueRange.h) follow that.
std::optional<long> smallIntegerConstant(const Expr& e);

}  // namespace facet
