// Lexer: turns material source text into tokens, each with its file:line:col.
//
// The lexer never fails hard: a byte it does not understand becomes an Error
// token carrying the message, and the parser reports it through the one
// diagnostic path. Numbers are kept as text; the parser converts them so that
// an out-of-range literal is reported where it stands.
#pragma once

#include "SourceLoc.h"

#include <string>
#include <string_view>
#include <vector>

namespace facet {

enum class TokenKind {
    Identifier,
    Number,
    // punctuation
    LBrace, RBrace, LParen, RParen, Comma, Semicolon, Equal, DotDot,
    Plus, Minus, Star, Slash, Caret,
    // keywords
    KwMaterial, KwInput, KwLet, KwIn,
    Error,  // text holds the message
    End,
};

const char* tokenKindName(TokenKind kind);

struct Token {
    TokenKind kind;
    std::string text;  // identifier / number spelling, or error message
    SourceLoc loc;
};

// Lexes the whole file. The last token is always End (also after errors).
std::vector<Token> lex(std::string_view source, const std::shared_ptr<const std::string>& file);

}  // namespace facet
