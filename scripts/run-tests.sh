#!/usr/bin/env bash
# The README's test command: install what is missing, build, run the tests.
#   scripts/run-tests.sh          the quick tier (ctest -L quick): every model,
#                                 backend, SIMD width and math mode, in minutes
#   scripts/run-tests.sh --long   every test: the quick tier, the long tier
#                                 (exhaustive statistics, the differential and
#                                 hard-case sweeps, fuzzing) and the ASan+UBSan
#                                 builds of the fuzz tests
# Extra arguments after the flag go to ctest (e.g. -R corpus).
# Tests write only inside build/ (tests/FacetAddTest.cmake).
set -euo pipefail
cd "$(dirname "$0")/.."
tier=quick
if [ "${1:-}" = --long ]; then
    tier=long
    shift
fi
scripts/install-deps.sh
if [ "$tier" = long ]; then
    scripts/build.sh -DFACET_SANITIZE_TESTS=ON
else
    scripts/build.sh -DFACET_SANITIZE_TESTS=OFF
fi
cd build
if [ "$tier" = long ]; then
    exec ctest --output-on-failure -j 2 "$@"
else
    exec ctest --output-on-failure -j 2 -L quick "$@"
fi
