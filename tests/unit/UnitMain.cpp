// doctest entry point of the front-end unit tests (facet_unit_tests).
//
// The suites (lexer, parser, checker, interpreter) are registered as separate
// ctest tests with --test-suite, so a failure names the stage that broke.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
