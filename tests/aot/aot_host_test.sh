#!/usr/bin/env bash
# Host objects of `facet build` against the JIT: for gold, plastic and
# brushed_metal in SIMD exact, SIMD fast, SIMD with a tolerance (the variant
# chosen on the host) and scalar exact, a plain C99
# program (aot_run.c, compiled by the system cc, linked against the object
# and libm only) evaluates the hard-case sample and 100k random pairs, samples
# wi for each lane's wo and evaluates the pdf of each pair, and
# facet_aot_reference requires its outputs to be the JIT kernel's bit for bit.
# satin_gaussian (gaussian's sampler inverts its CDF by Newton steps in IR)
# in SIMD exact only.
# Also: the objects reference no symbol outside themselves but libm's; and
# gold built for other x86_64 CPUs and features that facet build accepts
# (--cpu native, x86-64, -x87, ...) runs correctly on this host.
set -euo pipefail
build=$1 source=$2
facet=$build/bin/facet reference=$build/tests/aot/facet_aot_reference
cc=${CC:-cc}
random=100000
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
for material in gold plastic brushed_metal satin_gaussian; do
  mat=$source/materials/$material.mat
  "$reference" inputs "$mat" "$material" "" $random "$work/$material.in"
  configs=("simd exact" "simd fast" "simd tolerance=1e-4" "scalar exact") has_sampler=1
  [ $material = satin_gaussian ] && configs=("simd exact")
  for config in "${configs[@]}"; do
    set -- $config
    backend=$1 math=$2 prefix=${material}_${1}_${2%%=*}
    options="backend=$backend;math=$math"
    [[ $math == tolerance=* ]] && options="backend=$backend;$math"
    "$facet" build "$mat" --backend "$backend" --math "$math" --prefix "$prefix" \
      -o "$work/$prefix.o" --header "$work/$prefix.h"
    # Self-contained: every undefined symbol must come from libm (none is expected).
    undefined=$(nm -u "$work/$prefix.o" | awk '{print $2}' | grep -v -x -E '(sin|cos|exp|log|pow|sqrt|atan2|expf|logf|powf|sqrtf)' || true)
    if [ -n "$undefined" ]; then
      echo "FAIL $prefix.o needs symbols outside itself and libm: $undefined"
      failed=1
    fi
    # Exported: the entry points and nothing else; the sampler's exactly
    # where the header says the object has them.
    expected="${prefix}_eval ${prefix}_eval_batch"
    [ $has_sampler = 1 ] && expected+=" ${prefix}_sample ${prefix}_sample_batch ${prefix}_pdf ${prefix}_pdf_batch"
    expected=$(tr ' ' '\n' <<<"$expected" | LC_ALL=C sort | tr '\n' ' ')
    exported=$(nm -g --defined-only "$work/$prefix.o" | awk '{print $3}' | LC_ALL=C sort | tr '\n' ' ')
    if [ "$exported" != "$expected" ]; then
      echo "FAIL $prefix.o exports '$exported', expected '$expected'"
      failed=1
    fi
    if ! grep -q "^#define ${prefix}_HAS_SAMPLER $has_sampler\$" "$work/$prefix.h"; then
      echo "FAIL $prefix.h does not say ${prefix}_HAS_SAMPLER $has_sampler"
      failed=1
    fi
    "$cc" -std=c99 -pedantic -Wall -Wextra -Werror -O2 -DAOT_PREFIX="$prefix" -include "$work/$prefix.h" \
      "$source/tests/aot/aot_run.c" "$work/$prefix.o" -lm -o "$work/$prefix.run"
    "$work/$prefix.run" "$work/$material.in" "$work/$prefix.out" || failed=1
    "$reference" same-as-jit "$mat" "$material" "$options" $random "$work/$prefix.out" || failed=1
  done
done

# Other x86_64 CPUs and features that `facet build` accepts give objects that
# run correctly here: --cpu native is the JIT's own CPU, so bit for bit the
# JIT's outputs; the others (a baseline CPU, -x87, an AVX-512 CPU with AVX
# turned off, no FMA or SSE4.1) are checked against the double interpreter
# as the aarch64 objects are. The AVX-512 CPU only where this host has the
# non-AVX extensions that CPU implies.
if [ "$(uname -m)" = x86_64 ]; then
  mat=$source/materials/gold.mat small=2000
  "$reference" inputs "$mat" gold "" $small "$work/gold_small.in"
  variants=("native|--cpu native" "base|--cpu x86-64" "nox87|--features -x87" "nofma|--features -fma,-sse4.1")
  flags=" $(grep -m1 '^flags' /proc/cpuinfo) "
  has_all=1
  # /proc/cpuinfo names LZCNT abm.
  for f in bmi1 bmi2 movbe adx abm popcnt sse4_2 rdseed clflushopt; do [[ $flags == *" $f "* ]] || has_all=0; done
  [ $has_all = 1 ] && variants+=("skxnoavx|--cpu skylake-avx512 --features -avx")
  for variant in "${variants[@]}"; do
    prefix=gold_${variant%%|*} args=${variant#*|}
    if ! "$facet" build "$mat" $args --prefix "$prefix" -o "$work/$prefix.o" --header "$work/$prefix.h"; then
      echo "FAIL facet build $args"
      failed=1
      continue
    fi
    "$cc" -std=c99 -O2 -DAOT_PREFIX="$prefix" -include "$work/$prefix.h" "$source/tests/aot/aot_run.c" \
      "$work/$prefix.o" -lm -o "$work/$prefix.run"
    "$work/$prefix.run" "$work/gold_small.in" "$work/$prefix.out" || { echo "FAIL $prefix ($args) did not run"; failed=1; continue; }
    mode=against-interpreter
    [ "${variant%%|*}" = native ] && mode=same-as-jit
    "$reference" $mode "$mat" gold "backend=simd;math=exact" $small "$work/$prefix.out" ||
      { echo "FAIL $prefix ($args): $mode"; failed=1; }
  done
fi
exit $failed
