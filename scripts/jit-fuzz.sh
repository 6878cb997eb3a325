#!/usr/bin/env bash
# A long JIT fuzz campaign under AddressSanitizer and UndefinedBehaviorSanitizer:
# builds facet_jit_fuzz_asan in ./build (configuring it first if needed) and runs
# it on COUNT random materials (default 2000), every compiled backend against the
# interpreter on hostile lanes. The seed defaults to the current time and is
# printed on the totals line, so a finding can be replayed with --seed.
#   scripts/jit-fuzz.sh [--seed S] [--count N] [--lanes L]
# Exit status: the fuzzer's (0 clean, 1 a finding, 2 usage); a sanitizer report
# stops the run with a non-zero status and the report on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -f build/CMakeCache.txt ] || cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
if ! cmake --build build --target help | grep -q 'facet_jit_fuzz_asan'; then
  echo "jit-fuzz.sh: build/ has no facet_jit_fuzz_asan (configured with FACET_SANITIZE_TESTS=OFF," \
       "or the compiler cannot link -fsanitize=address,undefined)" >&2
  exit 1
fi
cmake --build build -j "$(nproc)" --target facet_jit_fuzz_asan
# The options of the sanitized tests (FACET_SANITIZE_ENV, tests/CMakeLists.txt).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:detect_stack_use_after_return=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
exec build/tests/differential/facet_jit_fuzz_asan --seed "$(date +%s)" --count 2000 "$@"
