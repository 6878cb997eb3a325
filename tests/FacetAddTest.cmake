# facet_add_test: the one way a test joins the suite.
#
#   facet_add_test(NAME <name> TIER quick|long COMMAND <cmd> [args...]
#                  [TIMEOUT <s>] [PROCESSORS <n>] [COST <c>] [LABELS <l>...]
#                  [ENVIRONMENT <VAR=value>...] [NO_CACHE]
#                  [FIXTURES_SETUP <f>...] [FIXTURES_REQUIRED <f>...]
#                  [PASS_REGULAR_EXPRESSION <re>] [SKIP_RETURN_CODE <code>])
#
# TIER: `quick` tests run on every change (`scripts/run-tests.sh`, which is
# `ctest -L quick`); `long` tests run only with `scripts/run-tests.sh --long`,
# which runs every test. The tier becomes a ctest label, and the test
# `tests_have_tiers` fails if any test lacks one.
#
# Every test runs in an environment that keeps it inside the build tree:
#   FACET_CACHE_DIR  build/test-cache, one cache shared by the whole run
#                    (NO_CACHE: empty, which disables the disk cache)
#   HOME             build/test-home, created empty before the run; the test
#                    `home_untouched` fails if anything was written there
#   XDG_CACHE_HOME   unset, so the default cache root would be under HOME
#   TMPDIR           build/test-tmp
#   CCACHE_DIR       build/test-tmp/ccache, and CMAKE_<LANG>_COMPILER_LAUNCHER
#                    unset: the tests that build C hosts or a CMake consumer do
#                    not write to a developer's ccache in HOME
# PROCESSORS: how many cores the test keeps busy (its threads), so that
# `ctest -j 2` does not start a second test beside a two-thread one.

set(FACET_TEST_HOME ${CMAKE_BINARY_DIR}/test-home)
set(FACET_TEST_TMP ${CMAKE_BINARY_DIR}/test-tmp)
set(FACET_TEST_CACHE ${CMAKE_BINARY_DIR}/test-cache)

function(facet_add_test)
  cmake_parse_arguments(PARSE_ARGV 0 arg "NO_CACHE"
                        "NAME;TIER;TIMEOUT;PROCESSORS;COST;PASS_REGULAR_EXPRESSION;SKIP_RETURN_CODE;WORKING_DIRECTORY"
                        "COMMAND;LABELS;ENVIRONMENT;FIXTURES_SETUP;FIXTURES_REQUIRED")
  if(NOT arg_NAME OR NOT arg_COMMAND)
    message(FATAL_ERROR "facet_add_test: NAME and COMMAND are required")
  endif()
  if(NOT arg_TIER MATCHES "^(quick|long)$")
    message(FATAL_ERROR "facet_add_test(${arg_NAME}): TIER must be quick or long, not '${arg_TIER}'")
  endif()
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "facet_add_test(${arg_NAME}): unknown arguments ${arg_UNPARSED_ARGUMENTS}")
  endif()
  if(arg_WORKING_DIRECTORY)
    add_test(NAME ${arg_NAME} COMMAND ${arg_COMMAND} WORKING_DIRECTORY ${arg_WORKING_DIRECTORY})
  else()
    add_test(NAME ${arg_NAME} COMMAND ${arg_COMMAND})
  endif()
  if(arg_NO_CACHE)
    set(cache "")
  else()
    set(cache ${FACET_TEST_CACHE})
  endif()
  if(NOT arg_TIMEOUT)
    set(arg_TIMEOUT 300)
  endif()
  set(labels ${arg_TIER} ${arg_LABELS})
  set(environment FACET_CACHE_DIR=${cache} HOME=${FACET_TEST_HOME} TMPDIR=${FACET_TEST_TMP}
                  CCACHE_DIR=${FACET_TEST_TMP}/ccache ${arg_ENVIRONMENT})
  set(fixtures facet_test_home ${arg_FIXTURES_REQUIRED})
  set_tests_properties(${arg_NAME} PROPERTIES
    LABELS "${labels}"
    TIMEOUT ${arg_TIMEOUT}
    ENVIRONMENT "${environment}"
    ENVIRONMENT_MODIFICATION "XDG_CACHE_HOME=unset:;CMAKE_C_COMPILER_LAUNCHER=unset:;CMAKE_CXX_COMPILER_LAUNCHER=unset:"
    FIXTURES_REQUIRED "${fixtures}")
  foreach(property PROCESSORS COST PASS_REGULAR_EXPRESSION SKIP_RETURN_CODE FIXTURES_SETUP)
    if(arg_${property})
      set_tests_properties(${arg_NAME} PROPERTIES ${property} "${arg_${property}}")
    endif()
  endforeach()
endfunction()

# The fixture every test requires: an empty HOME and TMPDIR before the run
# (tables in the shared test cache stay: they are checked on every read),
# and afterwards the check that HOME is still empty.
add_test(NAME test_home_setup
         COMMAND ${CMAKE_COMMAND} -DHOME=${FACET_TEST_HOME} -DTMP=${FACET_TEST_TMP} -DCACHE=${FACET_TEST_CACHE}
                 -DMODE=setup -P ${CMAKE_CURRENT_LIST_DIR}/TestHome.cmake)
add_test(NAME home_untouched
         COMMAND ${CMAKE_COMMAND} -DHOME=${FACET_TEST_HOME} -DMODE=check -P ${CMAKE_CURRENT_LIST_DIR}/TestHome.cmake)
set_tests_properties(test_home_setup PROPERTIES LABELS quick FIXTURES_SETUP facet_test_home)
set_tests_properties(home_untouched PROPERTIES LABELS quick FIXTURES_CLEANUP facet_test_home)

# Every test carries a tier label (a test added with plain add_test would
# run in neither tier's accounting).
add_test(NAME tests_have_tiers
         COMMAND ${CMAKE_COMMAND} -DCTEST=${CMAKE_CTEST_COMMAND} -DBUILD=${CMAKE_BINARY_DIR}
                 -P ${CMAKE_CURRENT_LIST_DIR}/TestTiers.cmake)
set_tests_properties(tests_have_tiers PROPERTIES LABELS quick)
