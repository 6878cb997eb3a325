// Lexer: hand-written scanner for the material language.
#include "Lexer.h"

#include <cctype>
#include <fmt/format.h>

namespace facet {

const char* tokenKindName(TokenKind kind) {
    switch (kind) {
        case TokenKind::Identifier: return "identifier";
        case TokenKind::Number: return "number";
        case TokenKind::LBrace: return "'{'";
        case TokenKind::RBrace: return "'}'";
        case TokenKind::LParen: return "'('";
        case TokenKind::RParen: return "')'";
        case TokenKind::Comma: return "','";
        case TokenKind::Semicolon: return "';'";
        case TokenKind::Equal: return "'='";
        case TokenKind::DotDot: return "'..'";
        case TokenKind::Plus: return "'+'";
        case TokenKind::Minus: return "'-'";
        case TokenKind::Star: return "'*'";
        case TokenKind::Slash: return "'/'";
        case TokenKind::Caret: return "'^'";
        case TokenKind::KwMaterial: return "'material'";
        case TokenKind::KwInput: return "'input'";
        case TokenKind::KwLet: return "'let'";
        case TokenKind::KwIn: return "'in'";
        case TokenKind::Error: return "invalid token";
        case TokenKind::End: return "end of file";
    }
    return "token";
}

namespace {

class Scanner {
public:
    Scanner(std::string_view src, std::shared_ptr<const std::string> file)
        : src_(src), file_(std::move(file)) {
        // A UTF-8 byte order mark (editors on Windows write one) is not text.
        if (src_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
    }

    std::vector<Token> run() {
        // The parser reports at most DiagnosticEngine::kMaxErrors errors, so
        // error tokens past that many are never read: stop there instead of
        // allocating one per bad byte of a large garbage file.
        constexpr size_t kMaxErrorTokens = 64;
        std::vector<Token> tokens;
        size_t errors = 0;
        for (;;) {
            skipSpaceAndComments(tokens);
            SourceLoc loc = here();
            if (pos_ >= src_.size() || errors >= kMaxErrorTokens) {
                tokens.push_back({TokenKind::End, "", loc});
                return tokens;
            }
            tokens.push_back(next(loc));
            errors += tokens.back().kind == TokenKind::Error;
        }
    }

private:
    SourceLoc here() const { return {file_, line_, col_}; }
    char peek(size_t ahead = 0) const {
        return pos_ + ahead < src_.size() ? src_[pos_ + ahead] : '\0';
    }
    // A line ends at "\n", "\r\n" or a lone "\r" (classic Mac files), so
    // that diagnostics point at the right line whatever the line endings.
    bool atLineBreak() const { return peek() == '\n' || (peek() == '\r' && peek(1) != '\n'); }
    void advance() {
        if (atLineBreak()) {
            ++line_;
            col_ = 1;
        } else {
            ++col_;
        }
        ++pos_;
    }

    void skipSpaceAndComments(std::vector<Token>& tokens) {
        while (pos_ < src_.size()) {
            char c = peek();
            if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
                advance();
            } else if (c == '/' && peek(1) == '/') {
                while (pos_ < src_.size() && peek() != '\n' && peek() != '\r') advance();
            } else if (c == '/' && peek(1) == '*') {
                SourceLoc start = here();
                advance();
                advance();
                bool closed = false;
                while (pos_ < src_.size()) {
                    if (peek() == '*' && peek(1) == '/') {
                        advance();
                        advance();
                        closed = true;
                        break;
                    }
                    advance();
                }
                if (!closed)
                    tokens.push_back({TokenKind::Error, "unterminated '/*' comment", start});
            } else {
                return;
            }
        }
    }

    // Echoes at most 40 bytes of user text in a message.
    static std::string clip(std::string_view text) {
        return text.size() <= 40 ? std::string(text) : std::string(text.substr(0, 40)) + "...";
    }

    static bool isIdentStart(char c) { return std::isalpha((unsigned char)c) || c == '_'; }
    static bool isIdentChar(char c) { return std::isalnum((unsigned char)c) || c == '_'; }
    static bool isDigit(char c) { return c >= '0' && c <= '9'; }

    Token next(const SourceLoc& loc) {
        char c = peek();
        if (isIdentStart(c)) {
            size_t start = pos_;
            while (pos_ < src_.size() && isIdentChar(peek())) advance();
            std::string text(src_.substr(start, pos_ - start));
            TokenKind kind = TokenKind::Identifier;
            if (text == "material") kind = TokenKind::KwMaterial;
            else if (text == "input") kind = TokenKind::KwInput;
            else if (text == "let") kind = TokenKind::KwLet;
            else if (text == "in") kind = TokenKind::KwIn;
            return {kind, std::move(text), loc};
        }
        // A number is digits [ '.' digits ] [ exponent ], or '.' digits. A '.'
        // directly followed by another '.' is the range operator, so "0..1"
        // lexes as 0, .., 1.
        if (isDigit(c) || (c == '.' && isDigit(peek(1)))) return number(loc);
        advance();
        switch (c) {
            case '{': return {TokenKind::LBrace, "{", loc};
            case '}': return {TokenKind::RBrace, "}", loc};
            case '(': return {TokenKind::LParen, "(", loc};
            case ')': return {TokenKind::RParen, ")", loc};
            case ',': return {TokenKind::Comma, ",", loc};
            case ';': return {TokenKind::Semicolon, ";", loc};
            case '=': return {TokenKind::Equal, "=", loc};
            case '+': return {TokenKind::Plus, "+", loc};
            case '-': return {TokenKind::Minus, "-", loc};
            case '*': return {TokenKind::Star, "*", loc};
            case '/': return {TokenKind::Slash, "/", loc};
            case '^': return {TokenKind::Caret, "^", loc};
            case '.':
                if (peek() == '.') {
                    advance();
                    return {TokenKind::DotDot, "..", loc};
                }
                return {TokenKind::Error, "unexpected '.' (a range is written 'lo .. hi')", loc};
            default: break;
        }
        if (std::isprint((unsigned char)c))
            return {TokenKind::Error, fmt::format("unexpected character '{}'", c), loc};
        return {TokenKind::Error,
                fmt::format("unexpected byte 0x{:02x}", static_cast<unsigned>(static_cast<unsigned char>(c))),
                loc};
    }

    Token number(const SourceLoc& loc) {
        size_t start = pos_;
        while (isDigit(peek())) advance();
        if (peek() == '.' && peek(1) != '.') {
            advance();
            while (isDigit(peek())) advance();
        }
        if (peek() == 'e' || peek() == 'E') {
            size_t save = pos_;
            int saveLine = line_, saveCol = col_;
            advance();
            if (peek() == '+' || peek() == '-') advance();
            if (!isDigit(peek())) {
                // "2e" or "2e+" is not a number; report it rather than guess.
                pos_ = save;
                line_ = saveLine;
                col_ = saveCol;
                advance();
                return {TokenKind::Error, "malformed number: exponent has no digits", loc};
            }
            while (isDigit(peek())) advance();
        }
        if (isIdentStart(peek())) {
            while (pos_ < src_.size() && isIdentChar(peek())) advance();
            return {TokenKind::Error, fmt::format("malformed number '{}'", clip(src_.substr(start, pos_ - start))), loc};
        }
        return {TokenKind::Number, std::string(src_.substr(start, pos_ - start)), loc};
    }

    std::string_view src_;
    std::shared_ptr<const std::string> file_;
    size_t pos_ = 0;
    int line_ = 1;
    int col_ = 1;
};

}  // namespace

std::vector<Token> lex(std::string_view source, const std::shared_ptr<const std::string>& file) {
    return Scanner(source, file).run();
}

}  // namespace facet
