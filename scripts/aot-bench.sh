#!/usr/bin/env bash
# ns/eval of `facet build` objects next to the JIT kernels of the same
# options (bench/aot_vs_jit.c), for the given materials (default: gold,
# plastic, brushed_metal) in SIMD exact, SIMD fast and scalar exact.
# Needs a built tree (scripts/build.sh).
#   scripts/aot-bench.sh [materials/X.mat ...]
set -euo pipefail
cd "$(dirname "$0")/.."
build=$PWD/build
materials=("$@")
((${#materials[@]})) || materials=(materials/gold.mat materials/plastic.mat materials/brushed_metal.mat)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for mat in "${materials[@]}"; do
  name=$(basename "$mat" .mat)
  for config in "simd exact" "simd fast" "scalar exact"; do
    set -- $config
    prefix=${name}_$1_$2
    "$build/bin/facet" build "$mat" --backend "$1" --math "$2" --prefix "$prefix" -o "$work/$prefix.o" --header "$work/$prefix.h"
    cc -std=c99 -O2 -D_POSIX_C_SOURCE=200112L -DAOT_PREFIX="$prefix" -include "$work/$prefix.h" -Iruntime/include bench/aot_vs_jit.c "$work/$prefix.o" \
      -L"$build/runtime" -lfacet -Wl,-rpath,"$build/runtime" -lm -o "$work/$prefix"
    lanes=65536 runs=31
    [ "$1" = scalar ] && lanes=8192
    FACET_CACHE_DIR= "$work/$prefix" "$mat" "backend=$1;math=$2;codegen=optimized" $lanes $runs
  done
done
