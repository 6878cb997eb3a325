// Lexer unit tests: token kinds, spellings and file:line:col locations.
//
// Locations matter because every diagnostic of the compiler is placed with
// them (SPEC 1: "file:line:col: error"); the number and range rules matter
// because `0..1` must be a range and `.5` a number, which a naive scanner
// that eats '.' into numbers gets wrong.
#include "Lexer.h"

#include <doctest/doctest.h>

#include <memory>
#include <string>
#include <vector>

using namespace facet;

namespace {

std::vector<Token> lexText(const std::string& src, const std::string& file = "t.mat") {
    return lex(src, std::make_shared<const std::string>(file));
}

// "kind:text@line:col" for compact comparisons.
std::vector<std::string> describe(const std::vector<Token>& toks) {
    std::vector<std::string> out;
    for (const Token& t : toks)
        out.push_back(std::string(tokenKindName(t.kind)) + ":" + t.text + "@" + std::to_string(t.loc.line) + ":" +
                      std::to_string(t.loc.col));
    return out;
}

}  // namespace

TEST_SUITE("lexer") {

TEST_CASE("an input declaration: kinds, spellings and columns") {
    auto toks = lexText("input roughness = 0.35 in 0 .. 1;");
    std::vector<std::string> expected = {
        "'input':input@1:1",   "identifier:roughness@1:7", "'=':=@1:17", "number:0.35@1:19",
        "'in':in@1:24",        "number:0@1:27",            "'..':..@1:29", "number:1@1:32",
        "';':;@1:33",          "end of file:@1:34",
    };
    CHECK(describe(toks) == expected);
}

TEST_CASE("every token carries the file name it came from") {
    auto toks = lexText("material m {}", "dir/gold.mat");
    for (const Token& t : toks) {
        REQUIRE(t.loc.file);
        CHECK(*t.loc.file == "dir/gold.mat");
    }
    CHECK(toks[1].loc.str() == "dir/gold.mat:1:10");
}

TEST_CASE("lines and columns across newlines, tabs and CRLF") {
    // Columns count bytes: a tab is one column, as in gcc and clang.
    auto toks = lexText("material m {\n\tndf = ggx(1);\r\n  }");
    REQUIRE(toks.size() == 12);
    CHECK(describe({toks[3]}) == std::vector<std::string>{"identifier:ndf@2:2"});
    CHECK(describe({toks[5]}) == std::vector<std::string>{"identifier:ggx@2:8"});
    CHECK(describe({toks[9]}) == std::vector<std::string>{"';':;@2:14"});
    CHECK(describe({toks[10]}) == std::vector<std::string>{"'}':}@3:3"});
    CHECK(toks[11].kind == TokenKind::End);
}

TEST_CASE("0..1 is a range, not the number 0. followed by .1") {
    auto toks = lexText("0..1");
    CHECK(describe(toks) == std::vector<std::string>{"number:0@1:1", "'..':..@1:2", "number:1@1:4", "end of file:@1:5"});
    // The same with fractional bounds and without spaces.
    toks = lexText("0.25..1.5");
    CHECK(describe(toks) ==
          std::vector<std::string>{"number:0.25@1:1", "'..':..@1:5", "number:1.5@1:7", "end of file:@1:10"});
}

TEST_CASE("number spellings: .5, 5., exponents") {
    for (const char* n : {".5", "5.", "1e-3", "1E+5", "2.5e10", "0", "007", "1.e2", "123456789012345678901234567890"}) {
        CAPTURE(n);
        auto toks = lexText(n);
        REQUIRE(toks.size() == 2);
        CHECK(toks[0].kind == TokenKind::Number);
        CHECK(toks[0].text == n);
    }
    // The minus sign is an operator, not part of the literal.
    auto toks = lexText("-1e-3");
    CHECK(describe(toks) == std::vector<std::string>{"'-':-@1:1", "number:1e-3@1:2", "end of file:@1:6"});
}

TEST_CASE("malformed numbers are one Error token each, at the number") {
    auto toks = lexText("2e + 3x");
    REQUIRE(toks.size() >= 3);
    CHECK(toks[0].kind == TokenKind::Error);
    CHECK(toks[0].text == "malformed number: exponent has no digits");
    CHECK(toks[0].loc.col == 1);
    // "2e" is reported, and lexing goes on after it.
    CHECK(toks[1].kind == TokenKind::Plus);
    CHECK(toks[2].kind == TokenKind::Error);
    CHECK(toks[2].text == "malformed number '3x'");
    CHECK(toks[2].loc.col == 6);
}

TEST_CASE("a lone '.' is an error that explains the range syntax") {
    auto toks = lexText("1 . 2");
    REQUIRE(toks.size() == 4);
    CHECK(toks[1].kind == TokenKind::Error);
    CHECK(toks[1].text == "unexpected '.' (a range is written 'lo .. hi')");
}

TEST_CASE("line and block comments are skipped, and lines still counted") {
    auto toks = lexText("// header\nlet /* inline */ a /* two\nlines */ = 1; // trailing\n");
    CHECK(describe(toks) == std::vector<std::string>{"'let':let@2:1", "identifier:a@2:18", "'=':=@3:10",
                                                     "number:1@3:12", "';':;@3:13", "end of file:@4:1"});
}

TEST_CASE("'/' alone is division; '/*' unterminated is reported at its start") {
    auto toks = lexText("a/b");
    CHECK(describe(toks) ==
          std::vector<std::string>{"identifier:a@1:1", "'/':/@1:2", "identifier:b@1:3", "end of file:@1:4"});
    toks = lexText("a\n  /* never closed\n\n");
    REQUIRE(toks.size() == 3);
    CHECK(toks[1].kind == TokenKind::Error);
    CHECK(toks[1].text == "unterminated '/*' comment");
    CHECK(toks[1].loc.line == 2);
    CHECK(toks[1].loc.col == 3);
    CHECK(toks[2].kind == TokenKind::End);
}

TEST_CASE("keywords are whole words only") {
    auto toks = lexText("material materials input inputs let letter in in_x");
    std::vector<TokenKind> kinds;
    for (const Token& t : toks) kinds.push_back(t.kind);
    CHECK(kinds == std::vector<TokenKind>{TokenKind::KwMaterial, TokenKind::Identifier, TokenKind::KwInput,
                                          TokenKind::Identifier, TokenKind::KwLet, TokenKind::Identifier,
                                          TokenKind::KwIn, TokenKind::Identifier, TokenKind::End});
}

TEST_CASE("stray bytes: printable ones are quoted, others shown in hex") {
    std::string src = "a @ ";
    src += '\0';
    src += " \xff";
    auto toks = lexText(src);
    REQUIRE(toks.size() == 5);
    CHECK(toks[1].text == "unexpected character '@'");
    CHECK(toks[2].text == "unexpected byte 0x00");
    CHECK(toks[2].loc.col == 5);
    CHECK(toks[3].text == "unexpected byte 0xff");
    CHECK(toks[4].kind == TokenKind::End);
}

TEST_CASE("the token list always ends with End, also for empty input") {
    auto toks = lexText("");
    REQUIRE(toks.size() == 1);
    CHECK(toks[0].kind == TokenKind::End);
    CHECK(toks[0].loc.line == 1);
    CHECK(toks[0].loc.col == 1);
    toks = lexText("/* x */ // y");
    REQUIRE(toks.size() == 1);
    CHECK(toks[0].kind == TokenKind::End);
}

}  // TEST_SUITE
