// Parser: one function per grammar rule, the rule written above it.
#include "Parser.h"

#include "Lexer.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <optional>

namespace facet {

namespace {

// Thrown to abandon the current statement after a syntax error was reported.
struct SyntaxError {};

constexpr int kMaxNesting = 200;

std::optional<ModelSlot> slotFromName(std::string_view name) {
    if (name == "ndf") return ModelSlot::Ndf;
    if (name == "masking") return ModelSlot::Masking;
    if (name == "fresnel") return ModelSlot::Fresnel;
    if (name == "energy") return ModelSlot::Energy;
    if (name == "diffuse") return ModelSlot::Diffuse;
    return std::nullopt;
}

class Parser {
public:
    Parser(std::vector<Token> tokens, DiagnosticEngine& diags) : tokens_(std::move(tokens)), diags_(diags) {}

    // program := material* EOF
    Program program(std::shared_ptr<const std::string> file) {
        Program prog;
        prog.file = std::move(file);
        while (!at(TokenKind::End) && !diags_.full()) {
            if (at(TokenKind::KwMaterial)) {
                material(prog);
            } else {
                report(peek(), fmt::format("expected 'material', found {}", describe(peek())));
                // Skip to the next 'material' keyword.
                while (!at(TokenKind::End) && !at(TokenKind::KwMaterial)) advance();
            }
        }
        if (prog.materials.empty() && !diags_.hasErrors())
            diags_.error(peek().loc, "file contains no material (expected 'material NAME { ... }')");
        return prog;
    }

private:
    // material := 'material' IDENT '{' statement* '}'
    void material(Program& prog) {
        advance();  // 'material'
        MaterialDecl decl;
        try {
            const Token& name = expect(TokenKind::Identifier, "a material name after 'material'");
            decl.loc = name.loc;
            decl.name = name.text;
            expect(TokenKind::LBrace, "'{' after the material name");
        } catch (SyntaxError&) {
            while (!at(TokenKind::End) && !at(TokenKind::KwMaterial)) advance();
            return;
        }
        while (!at(TokenKind::RBrace) && !at(TokenKind::End) && !diags_.full()) {
            if (at(TokenKind::KwMaterial)) {
                report(peek(), fmt::format("missing '}}' to close material '{}'", decl.name));
                decl.hasSyntaxErrors = true;
                prog.materials.push_back(std::move(decl));
                return;
            }
            try {
                decl.statements.push_back(statement());
            } catch (SyntaxError&) {
                decl.hasSyntaxErrors = true;
                synchronize();
            }
            if (lobeHadErrors_) decl.hasSyntaxErrors = true, lobeHadErrors_ = false;
        }
        if (at(TokenKind::End)) {
            report(peek(), fmt::format("missing '}}' to close material '{}'", decl.name));
            decl.hasSyntaxErrors = true;
        }
        else
            advance();  // '}'
        prog.materials.push_back(std::move(decl));
    }

    // statement := 'input' IDENT '=' expr [ 'in' expr '..' expr ] ';'
    //            | 'let' IDENT '=' expr ';'
    //            | model-statement | lobe-option | lobe | bsdf
    Stmt statement() {
        if (at(TokenKind::KwInput)) {
            advance();
            InputDecl in;
            const Token& name = expect(TokenKind::Identifier, "an input name after 'input'");
            in.loc = name.loc;
            in.name = name.text;
            expect(TokenKind::Equal, fmt::format("'=' and a default value after input '{}'", in.name));
            in.defaultValue = expression();
            if (match(TokenKind::KwIn)) {
                in.lo = expression();
                expect(TokenKind::DotDot, "'..' between the range bounds");
                in.hi = expression();
            }
            expect(TokenKind::Semicolon, "';' after the input declaration");
            return in;
        }
        if (at(TokenKind::KwLet)) {
            advance();
            LetDecl let;
            const Token& name = expect(TokenKind::Identifier, "a name after 'let'");
            let.loc = name.loc;
            let.name = name.text;
            expect(TokenKind::Equal, fmt::format("'=' after let '{}'", let.name));
            let.value = expression();
            expect(TokenKind::Semicolon, "';' after the let statement");
            return let;
        }
        if (at(TokenKind::Identifier) && peek().text == "lobe" && peek(1).kind == TokenKind::Identifier) return lobe();
        if (at(TokenKind::Identifier) && peek().text == "bsdf" && peek(1).kind == TokenKind::Equal) return bsdf();
        if (at(TokenKind::Identifier) && isLobeOption(peek().text)) return lobeOption();
        if (at(TokenKind::Identifier))
            return modelStatement("input, let, lobe, bsdf, ndf, masking, fresnel, energy, diffuse, scatter or thin");
        report(peek(), fmt::format("expected a statement, found {}", describe(peek())));
        throw SyntaxError{};
    }

    // model-statement := SLOT '=' model ';'     SLOT := ndf | masking | fresnel | energy | diffuse
    ModelStmt modelStatement(const char* expected) {
        const Token& head = peek();
        std::optional<ModelSlot> slot = slotFromName(head.text);
        if (!slot) {
            report(head, fmt::format("unknown statement '{}' (expected {})", head.text, expected));
            throw SyntaxError{};
        }
        advance();
        ModelStmt stmt;
        stmt.loc = head.loc;
        stmt.slot = *slot;
        expect(TokenKind::Equal, fmt::format("'=' after '{}'", modelSlotName(*slot)));
        model(stmt);
        expect(TokenKind::Semicolon, fmt::format("';' after the {} statement", modelSlotName(*slot)));
        return stmt;
    }

    // lobe-option := ('scatter' | 'thin') '=' IDENT ';'
    LobeOptionStmt lobeOption() {
        LobeOptionStmt stmt;
        const Token& head = advance();
        stmt.loc = head.loc;
        stmt.option = head.text;
        expect(TokenKind::Equal, fmt::format("'=' after '{}'", stmt.option));
        const Token& value = expect(TokenKind::Identifier, fmt::format("a word after '{} =' (e.g. {})", stmt.option,
                                                                        stmt.option == "thin" ? "true" : "both"));
        stmt.valueLoc = value.loc;
        stmt.value = value.text;
        expect(TokenKind::Semicolon, fmt::format("';' after the {} statement", stmt.option));
        return stmt;
    }

    // lobe := 'lobe' IDENT '{' (model-statement | lobe-option)* '}'
    // A syntax error inside the block skips that statement only (the rest
    // of the lobe still parses); the material is marked as having errors.
    LobeDecl lobe() {
        advance();  // 'lobe'
        LobeDecl decl;
        const Token& name = expect(TokenKind::Identifier, "a lobe name after 'lobe'");
        decl.loc = name.loc;
        decl.name = name.text;
        expect(TokenKind::LBrace, fmt::format("'{{' after lobe '{}'", decl.name));
        while (!at(TokenKind::RBrace) && !at(TokenKind::End) && !at(TokenKind::KwMaterial) && !diags_.full()) {
            try {
                if (at(TokenKind::KwInput) || at(TokenKind::KwLet) ||
                    (at(TokenKind::Identifier) && (peek().text == "lobe" || peek().text == "bsdf"))) {
                    report(peek(), fmt::format("'{}' belongs at material level, not inside lobe '{}'", peek().text,
                                               decl.name));
                    throw SyntaxError{};
                }
                if (!at(TokenKind::Identifier)) {
                    report(peek(), fmt::format("expected a model statement in lobe '{}', found {}", decl.name,
                                               describe(peek())));
                    throw SyntaxError{};
                }
                if (isLobeOption(peek().text))
                    decl.options.push_back(lobeOption());
                else
                    decl.statements.push_back(
                        modelStatement("ndf, masking, fresnel, energy, diffuse, scatter or thin inside a lobe"));
            } catch (SyntaxError&) {
                lobeHadErrors_ = true;
                synchronize();
            }
        }
        expect(TokenKind::RBrace, fmt::format("'}}' to close lobe '{}'", decl.name));
        return decl;
    }

    // bsdf := 'bsdf' '=' expr ';'      (lobe names, '+', weight '*', mix(...), layer(...))
    BsdfStmt bsdf() {
        BsdfStmt stmt;
        stmt.loc = advance().loc;  // 'bsdf'
        advance();                 // '='
        stmt.value = expression();
        expect(TokenKind::Semicolon, "';' after the bsdf statement");
        return stmt;
    }

    // model := IDENT [ '(' [ argument { ',' argument } ] ')' ]
    void model(ModelStmt& stmt) {
        const Token& name = expect(TokenKind::Identifier, fmt::format("a model name after '{} ='", modelSlotName(stmt.slot)));
        stmt.modelLoc = name.loc;
        stmt.model = name.text;
        if (match(TokenKind::LParen)) stmt.args = argumentList();
    }

    // argument-list := [ argument { ',' argument } ] ')'
    // argument      := [ IDENT '=' ] expr
    std::vector<Argument> argumentList() {
        std::vector<Argument> args;
        if (match(TokenKind::RParen)) return args;
        for (;;) {
            Argument arg;
            if (at(TokenKind::Identifier) && peek(1).kind == TokenKind::Equal) {
                arg.name = peek().text;
                arg.nameLoc = peek().loc;
                advance();
                advance();
            }
            arg.value = expression();
            args.push_back(std::move(arg));
            if (match(TokenKind::Comma)) continue;
            expect(TokenKind::RParen, "',' or ')' in the argument list");
            return args;
        }
    }

    // expr := additive
    ExprPtr expression() {
        if (++depth_ > kMaxNesting) {
            report(peek(), fmt::format("expression nested too deeply (more than {} levels)", kMaxNesting));
            throw SyntaxError{};
        }
        ExprPtr e = additive();
        --depth_;
        return e;
    }

    // additive := multiplicative { ('+' | '-') multiplicative }
    ExprPtr additive() {
        ExprPtr lhs = multiplicative();
        while (at(TokenKind::Plus) || at(TokenKind::Minus)) {
            Token op = advance();
            ExprPtr rhs = multiplicative();
            lhs = bounded(std::make_shared<BinaryExpr>(op.loc, op.kind == TokenKind::Plus ? BinaryOp::Add : BinaryOp::Sub,
                                                       lhs, rhs),
                          {&lhs, &rhs});
        }
        return lhs;
    }

    // multiplicative := unary { ('*' | '/') unary }
    ExprPtr multiplicative() {
        ExprPtr lhs = unary();
        while (at(TokenKind::Star) || at(TokenKind::Slash)) {
            Token op = advance();
            ExprPtr rhs = unary();
            lhs = bounded(std::make_shared<BinaryExpr>(op.loc, op.kind == TokenKind::Star ? BinaryOp::Mul : BinaryOp::Div,
                                                       lhs, rhs),
                          {&lhs, &rhs});
        }
        return lhs;
    }

    // unary := '-' unary | power        (so -x^2 is -(x^2), as in mathematics)
    ExprPtr unary() {
        if (at(TokenKind::Minus)) {
            Token op = advance();
            if (++depth_ > kMaxNesting) {
                report(op, fmt::format("expression nested too deeply (more than {} levels)", kMaxNesting));
                throw SyntaxError{};
            }
            ExprPtr operand = unary();
            --depth_;
            return bounded(std::make_shared<UnaryExpr>(op.loc, operand), {&operand});
        }
        return power();
    }

    // power := primary [ '^' unary ]    (right-associative: 2^3^2 = 2^9)
    ExprPtr power() {
        ExprPtr base = primary();
        if (at(TokenKind::Caret)) {
            Token op = advance();
            if (++depth_ > kMaxNesting) {
                report(op, fmt::format("expression nested too deeply (more than {} levels)", kMaxNesting));
                throw SyntaxError{};
            }
            ExprPtr exponent = unary();
            --depth_;
            return bounded(std::make_shared<BinaryExpr>(op.loc, BinaryOp::Pow, base, exponent), {&base, &exponent});
        }
        return base;
    }

    // primary := NUMBER | IDENT | IDENT '(' argument-list | '(' expr ')'
    ExprPtr primary() {
        const Token& tok = peek();
        switch (tok.kind) {
            case TokenKind::Number: {
                advance();
                errno = 0;
                double v = std::strtod(tok.text.c_str(), nullptr);
                if (std::isinf(v)) {
                    report(tok, fmt::format("number '{}' is too large",
                                            tok.text.size() <= 40 ? tok.text : tok.text.substr(0, 40) + "..."));
                    throw SyntaxError{};
                }
                return std::make_shared<NumberExpr>(tok.loc, v);
            }
            case TokenKind::Identifier: {
                Token name = advance();
                if (match(TokenKind::LParen)) {
                    auto call = std::make_shared<CallExpr>(name.loc, name.text, argumentList());
                    int depth = 0;
                    for (const Argument& a : call->args) depth = std::max(depth, a.value->depth);
                    call->depth = depth + 1;
                    if (call->depth > kMaxNesting) {
                        diags_.error(call->loc, fmt::format("expression nested too deeply (more than {} levels); "
                                                            "split it with 'let'",
                                                            kMaxNesting));
                        throw SyntaxError{};
                    }
                    return call;
                }
                return std::make_shared<NameExpr>(name.loc, name.text);
            }
            case TokenKind::LParen: {
                advance();
                ExprPtr inner = expression();
                expect(TokenKind::RParen, "')' to close '('");
                return inner;
            }
            default:
                report(tok, fmt::format("expected an expression, found {}", describe(tok)));
                throw SyntaxError{};
        }
    }

    // ---- helpers ----

    // Sets e's depth from its children and rejects trees deeper than
    // kMaxNesting: a left-associative chain (1+1+...+1) nests without any
    // parenthesis, and every later pass walks the tree recursively.
    ExprPtr bounded(ExprPtr e, std::initializer_list<const ExprPtr*> children) {
        int depth = 0;
        for (const ExprPtr* c : children) depth = std::max(depth, (*c)->depth);
        e->depth = depth + 1;
        if (e->depth > kMaxNesting) {
            diags_.error(e->loc, fmt::format("expression nested too deeply (more than {} levels); split it with 'let'",
                                             kMaxNesting));
            throw SyntaxError{};
        }
        return e;
    }

    // After a syntax error: skip past the next ';' (or up to a '}' that
    // closes the material) so that the next statement parses cleanly.
    void synchronize() {
        depth_ = 0;
        int braces = 0;
        while (!at(TokenKind::End)) {
            if (at(TokenKind::Semicolon) && braces == 0) {
                advance();
                return;
            }
            if (at(TokenKind::RBrace)) {
                if (braces == 0) return;
                --braces;
            }
            if (at(TokenKind::LBrace)) ++braces;
            if (at(TokenKind::KwMaterial) && braces == 0) return;
            advance();
        }
    }

    static std::string describe(const Token& t) {
        switch (t.kind) {
            case TokenKind::Identifier: return fmt::format("'{}'", t.text);
            case TokenKind::Number: return fmt::format("number '{}'", t.text);
            case TokenKind::End: return "end of file";
            case TokenKind::Error: return "an invalid token";
            default: return tokenKindName(t.kind);
        }
    }

    // Reports at `t`; an Error token's own message takes precedence, since
    // it says what is really wrong.
    void report(const Token& t, const std::string& message) {
        if (t.kind == TokenKind::Error) {
            diags_.error(t.loc, t.text);
        } else {
            diags_.error(t.loc, message);
        }
    }

    const Token& peek(size_t ahead = 0) const {
        size_t i = std::min(pos_ + ahead, tokens_.size() - 1);
        return tokens_[i];
    }
    bool at(TokenKind k) const { return peek().kind == k; }
    const Token& advance() {
        const Token& t = tokens_[pos_];
        if (pos_ + 1 < tokens_.size()) ++pos_;
        return t;
    }
    bool match(TokenKind k) {
        if (!at(k)) return false;
        advance();
        return true;
    }
    const Token& expect(TokenKind k, const std::string& what) {
        if (at(k)) return advance();
        report(peek(), fmt::format("expected {}, found {}", what, describe(peek())));
        throw SyntaxError{};
    }

    std::vector<Token> tokens_;
    DiagnosticEngine& diags_;
    size_t pos_ = 0;
    int depth_ = 0;
    bool lobeHadErrors_ = false;  // a statement inside a lobe block was dropped
};

}  // namespace

Program parseProgram(std::string_view source, const std::string& path, DiagnosticEngine& diags) {
    auto file = std::make_shared<const std::string>(path);
    return Parser(lex(source, file), diags).program(file);
}

}  // namespace facet
