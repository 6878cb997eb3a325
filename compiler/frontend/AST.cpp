// AST: names of enums, default traversal, and the expression printer.
#include "AST.h"

#include "Builtins.h"
#include "Diagnostics.h"

#include <cmath>
#include <fmt/format.h>

namespace facet {

const char* valueTypeName(ValueType t) {
    switch (t) {
        case ValueType::Float: return "float";
        case ValueType::Rgb: return "rgb";
        case ValueType::Unknown: return "<unknown>";
    }
    return "?";
}

const char* binaryOpSpelling(BinaryOp op) {
    switch (op) {
        case BinaryOp::Add: return "+";
        case BinaryOp::Sub: return "-";
        case BinaryOp::Mul: return "*";
        case BinaryOp::Div: return "/";
        case BinaryOp::Pow: return "^";
    }
    return "?";
}

const char* modelSlotName(ModelSlot slot) {
    switch (slot) {
        case ModelSlot::Ndf: return "ndf";
        case ModelSlot::Masking: return "masking";
        case ModelSlot::Fresnel: return "fresnel";
        case ModelSlot::Energy: return "energy";
        case ModelSlot::Diffuse: return "diffuse";
    }
    return "?";
}

bool isLobeOption(const std::string& name) { return name == "scatter" || name == "thin"; }

void ExprVisitor::visit(const Expr& e) {
    switch (e.kind) {
        case ExprKind::Number: return visitNumber(static_cast<const NumberExpr&>(e));
        case ExprKind::Name: return visitName(static_cast<const NameExpr&>(e));
        case ExprKind::Unary: return visitUnary(static_cast<const UnaryExpr&>(e));
        case ExprKind::Binary: return visitBinary(static_cast<const BinaryExpr&>(e));
        case ExprKind::Call: return visitCall(static_cast<const CallExpr&>(e));
    }
    internal_error << "unknown expression kind";
}

ExprPtr ExprMutator::mutate(const ExprPtr& e) {
    switch (e->kind) {
        case ExprKind::Number: return mutateNumber(std::static_pointer_cast<NumberExpr>(e));
        case ExprKind::Name: return mutateName(std::static_pointer_cast<NameExpr>(e));
        case ExprKind::Unary: return mutateUnary(std::static_pointer_cast<UnaryExpr>(e));
        case ExprKind::Binary: return mutateBinary(std::static_pointer_cast<BinaryExpr>(e));
        case ExprKind::Call: return mutateCall(std::static_pointer_cast<CallExpr>(e));
    }
    internal_error << "unknown expression kind";
}

ExprPtr ExprMutator::mutateUnary(const std::shared_ptr<UnaryExpr>& e) {
    ExprPtr operand = mutate(e->operand);
    if (operand == e->operand) return e;
    auto copy = std::make_shared<UnaryExpr>(*e);
    copy->operand = operand;
    return copy;
}

ExprPtr ExprMutator::mutateBinary(const std::shared_ptr<BinaryExpr>& e) {
    ExprPtr lhs = mutate(e->lhs), rhs = mutate(e->rhs);
    if (lhs == e->lhs && rhs == e->rhs) return e;
    auto copy = std::make_shared<BinaryExpr>(*e);
    copy->lhs = lhs;
    copy->rhs = rhs;
    return copy;
}

ExprPtr ExprMutator::mutateCall(const std::shared_ptr<CallExpr>& e) {
    bool changed = false;
    std::vector<Argument> args = e->args;
    for (Argument& a : args) {
        ExprPtr v = mutate(a.value);
        changed |= v != a.value;
        a.value = v;
    }
    if (!changed) return e;
    auto copy = std::make_shared<CallExpr>(*e);
    copy->args = std::move(args);
    return copy;
}

namespace {
class Printer : public ExprVisitor {
public:
    std::string out;
    void visitNumber(const NumberExpr& e) override { out += fmt::format("{}", e.value); }
    void visitName(const NameExpr& e) override { out += e.name; }
    void visitUnary(const UnaryExpr& e) override {
        out += "-";
        visit(*e.operand);
    }
    void visitBinary(const BinaryExpr& e) override {
        out += "(";
        visit(*e.lhs);
        out += fmt::format(" {} ", binaryOpSpelling(e.op));
        visit(*e.rhs);
        out += ")";
    }
    void visitCall(const CallExpr& e) override {
        out += e.callee + "(";
        for (size_t i = 0; i < e.args.size(); ++i) {
            if (i) out += ", ";
            if (!e.args[i].name.empty()) out += e.args[i].name + " = ";
            visit(*e.args[i].value);
        }
        out += ")";
    }
};
}  // namespace

std::string printExpr(const Expr& e) {
    Printer p;
    p.visit(e);
    return p.out;
}

std::optional<long> smallIntegerConstant(const Expr& e) {
    if (e.kind != ExprKind::Number) return std::nullopt;
    double v = static_cast<const NumberExpr&>(e).value;
    if (v != std::floor(v) || std::fabs(v) > 64) return std::nullopt;
    return long(v);
}

}  // namespace facet
