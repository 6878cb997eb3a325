#!/usr/bin/env bash
# aarch64 objects of `facet build` (NEON, SIMD width 4): aot_run.c linked
# with Debian's gcc-aarch64-linux-gnu against the object and libm, run under
# qemu-user on the hard-case sample and 100k random pairs of gold, plastic
# and brushed_metal (exact mode); facet_aot_reference checks the outputs
# against the double interpreter as the hard-case tests check the host JIT
# (same bound; no NaN, Inf or negative output; invalid lanes 0 and counted),
# and the objects' samplers (sample and pdf, batch and one lane, and their
# argument and invalid-lane conventions in aot_run.c) against the host JIT
# kernel's sampler. Also gold built with -neon and with +strict-align.
# Installs the toolchain with apt if it is missing; exits 77 (skipped) with a
# message only if that is impossible.
set -euo pipefail
build=$1 source=$2
facet=$build/bin/facet reference=$build/tests/aot/facet_aot_reference
packages="gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user"
if ! command -v aarch64-linux-gnu-gcc >/dev/null || ! command -v qemu-aarch64 >/dev/null; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo -n"
  echo "installing $packages"
  if ! { $sudo_cmd apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends $packages; } >/dev/null 2>&1 ||
     ! command -v aarch64-linux-gnu-gcc >/dev/null || ! command -v qemu-aarch64 >/dev/null; then
    echo "SKIPPED: apt-get could not install $packages (needed to link and run aarch64 objects)"
    exit 77
  fi
fi
random=100000
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
for material in gold plastic brushed_metal; do
  mat=$source/materials/$material.mat
  prefix=${material}_a64
  "$reference" inputs "$mat" "$material" "" $random "$work/$material.in"
  "$facet" build "$mat" --target aarch64-linux-gnu --backend simd --math exact --prefix "$prefix" \
    -o "$work/$prefix.o" --header "$work/$prefix.h"
  grep -q 'aarch64-unknown-linux-gnu, cpu generic, SIMD width 4' "$work/$prefix.h" ||
    { echo "FAIL $prefix.h does not record target aarch64, SIMD width 4"; failed=1; }
  undefined=$(aarch64-linux-gnu-nm -u "$work/$prefix.o" | awk '{print $2}')
  [ -z "$undefined" ] || { echo "FAIL $prefix.o needs symbols outside itself: $undefined"; failed=1; }
  aarch64-linux-gnu-gcc -std=c99 -pedantic -Wall -Wextra -Werror -O2 -static -DAOT_PREFIX="$prefix" \
    -include "$work/$prefix.h" "$source/tests/aot/aot_run.c" "$work/$prefix.o" -lm -o "$work/$prefix.run"
  qemu-aarch64 "$work/$prefix.run" "$work/$material.in" "$work/$prefix.out" || failed=1
  "$reference" against-interpreter "$mat" "$material" "backend=simd;math=exact" $random "$work/$prefix.out" || failed=1
done

# Features `facet build` accepts for aarch64 besides the default: without
# NEON (the 4-lane kernel becomes scalar FP code) and with strict alignment;
# the objects run and meet the same bounds.
mat=$source/materials/gold.mat small=2000
"$reference" inputs "$mat" gold "" $small "$work/gold_small.in"
for features in -neon +strict-align; do
  prefix=gold_a64_${features:1}
  prefix=${prefix//-/_}
  "$facet" build "$mat" --target aarch64-linux-gnu --features "$features" --prefix "$prefix" \
    -o "$work/$prefix.o" --header "$work/$prefix.h" || { echo "FAIL facet build --features $features"; failed=1; continue; }
  aarch64-linux-gnu-gcc -std=c99 -O2 -static -DAOT_PREFIX="$prefix" -include "$work/$prefix.h" \
    "$source/tests/aot/aot_run.c" "$work/$prefix.o" -lm -o "$work/$prefix.run"
  qemu-aarch64 "$work/$prefix.run" "$work/gold_small.in" "$work/$prefix.out" || { echo "FAIL $prefix did not run"; failed=1; continue; }
  "$reference" against-interpreter "$mat" gold "backend=simd;math=exact" $small "$work/$prefix.out" ||
    { echo "FAIL $prefix: against the interpreter"; failed=1; }
done
exit $failed
