#!/usr/bin/env bash
# `facet build` on bad input: each mistake is one line on stderr naming what
# is wrong, with exit 2 (usage: options, target, CPU, feature, an output that
# cannot be written) or 65 (material file error, including a material the
# file does not have), and no output file is left behind or half-replaced.
# Also the other outputs (--emit) and the header as C99 and C++. The argument
# fuzz (aot_fuzz_test.sh) is a test of its own, aot_fuzz, in the long tier.
set -euo pipefail
build=$(cd "$1" && pwd) source=$(cd "$2" && pwd)  # absolute: some cases run from other directories
facet=$build/bin/facet
gold=$source/materials/gold.mat
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
fail() { echo "FAIL: $*"; failed=1; }

# expect CODE PATTERN ARGS...: exit code CODE, one stderr line matching PATTERN, no file in $work/out.
expect() {
  local code=$1 pattern=$2
  shift 2
  rm -rf "$work/out" && mkdir "$work/out"
  local got=0
  "$facet" build "$@" 2>"$work/err" >/dev/null || got=$?
  local lines
  lines=$(wc -l <"$work/err")
  [ "$got" = "$code" ] || fail "build $*: exit $got, expected $code ($(cat "$work/err"))"
  [ "$lines" = 1 ] || fail "build $*: $lines lines on stderr, expected one: $(cat "$work/err")"
  grep -q -e "$pattern" "$work/err" || fail "build $*: stderr '$(cat "$work/err")' does not match '$pattern'"
  [ -z "$(ls -A "$work/out")" ] || fail "build $*: left $(ls -A "$work/out")"
  echo "ok ($got): $(cat "$work/err")" | cut -c1-160
}

o=$work/out/g.o h=$work/out/g.h
expect 2 "unknown target 'sparc99-linux-gnu' (this LLVM has: .*aarch64.*x86-64" "$gold" --target sparc99-linux-gnu -o "$o" --header "$h"
expect 2 "unknown CPU 'pentium9' for aarch64 (CPUs: .*cortex-a72" "$gold" --target aarch64-linux-gnu --cpu pentium9 -o "$o"
expect 2 "unknown CPU 'cortex-a72' for x86_64 (CPUs: .*skylake" "$gold" --cpu cortex-a72 -o "$o"
expect 2 "unknown feature '+avx9' for x86_64 .*avx2" "$gold" --features +avx9 -o "$o"
expect 2 "unknown feature 'neon' for aarch64 (write +NAME or -NAME" "$gold" --target aarch64-linux-gnu --features neon -o "$o"
# Targets, CPUs and features Facet cannot serve are refused before LLVM
# generates code (it used to abort, report an internal error or print raw
# LLVM errors): other architectures, 32-bit pointers, x86 CPUs without
# 64-bit mode, features leaving no SSE2 (x86_64) or no FP (aarch64).
served="it builds for x86_64 and aarch64 (little-endian, 64-bit pointers)"
for t in amdgcn-amd-amdhsa hexagon ve xcore bpf i686-linux-gnu aarch64_be-linux-gnu; do
  expect 2 "facet: error: target '$t' (.*) is not one Facet builds for; $served" "$gold" --target $t -o "$o" --header "$h"
done
expect 2 "facet: error: target 'x86_64-linux-gnux32' has 32-bit pointers" "$gold" --target x86_64-linux-gnux32 -o "$o"
expect 2 "facet: error: target 'aarch64-linux-gnu_ilp32' has 32-bit pointers" "$gold" --target aarch64-linux-gnu_ilp32 -o "$o"
x86=""
[ "$(uname -m)" = x86_64 ] || x86="--target x86_64-linux-gnu"
for cpu in pentium i386 i686 pentium4; do
  expect 2 "facet: error: CPU '$cpu' for x86_64 cannot run 64-bit code" "$gold" $x86 --cpu $cpu -o "$o"
done
expect 2 "facet: error: CPU '.*' for x86_64 with features '-64bit-mode' cannot run 64-bit code" "$gold" $x86 --features -64bit-mode -o "$o"
for f in -sse2 -sse +x87,-sse2; do
  expect 2 "facet: error: CPU '.*' for x86_64 with features '$f' has no SSE2" "$gold" $x86 --features $f -o "$o"
done
expect 2 "with features '+soft-float' uses soft-float, which passes floats in integer registers" "$gold" $x86 --features +soft-float -o "$o"
expect 2 "CPU 'x86-64' for x86_64 with features '+avx512f,-evex512' has avx512f without evex512 or avx512vl" \
  "$gold" --target x86_64-linux-gnu --cpu x86-64 --features +avx512f,-evex512 -o "$o"
expect 2 "CPU 'generic' for aarch64 with features '-fp-armv8' has no floating point" "$gold" --target aarch64-linux-gnu --features -fp-armv8 -o "$o"
expect 2 "CPU 'generic' for aarch64 with features '+reserve-x18,+reserve-x3' reserves x3 (feature reserve-x3), an argument register" \
  "$gold" --target aarch64-linux-gnu --features +reserve-x18,+reserve-x3 -o "$o"
other=aarch64-linux-gnu
[ "$(uname -m)" = x86_64 ] || other=x86_64-linux-gnu
expect 2 "facet: error: --cpu native means this machine's CPU (.*), and target '$other' is another architecture" \
  "$gold" --target $other --cpu native -o "$o"
expect 65 "no material named 'silver' in .*gold.mat (materials: gold)" "$gold" --material silver -o "$o" --header "$h"
printf 'material broken {\n    ndf = ggx(;\n}\n' >"$work/broken.mat"
expect 65 "broken.mat:2:" "$work/broken.mat" -o "$o"
expect 2 "backend 'interp' is not scalar or simd" "$gold" --backend interp -o "$o"
expect 2 "math 'precise' is not exact, fast or tolerance=X" "$gold" --math precise -o "$o"
expect 2 "tolerance '-1' is not a positive number" "$gold" --math tolerance=-1 -o "$o"
expect 2 "prefix '9lives' is not a C identifier" "$gold" --prefix 9lives -o "$o"
expect 2 "emit 'exe' is not obj, asm, llvm-ir or bitcode" "$gold" --emit exe -o "$o"
expect 2 "material 'gold' has no input 'shine'" "$gold" --set shine=1 -o "$o"
expect 2 "-o OUT is required" "$gold" --header "$h"
touch "$work/file"
expect 2 "facet: error: cannot write .*/file/g.o: Not a directory" "$gold" -o "$work/file/g.o" --header "$h"
# The object can be written, the header cannot: neither appears.
expect 2 "facet: error: cannot write .*/file/g.h: Not a directory" "$gold" -o "$o" --header "$work/file/g.h"

# Outputs go only to new paths or over regular files: a FIFO, a directory,
# a symlink (also one to /dev/null or to a directory) is refused as it is,
# untouched and unread, and so is an output that is the material file or
# the other output (by inode for existing files, by normalized path for new ones).
expect_kept() {  # PATTERN ARGS...: exit 2, one line matching PATTERN, nothing new in $work/out
  local pattern=$1 before got=0
  shift
  before=$(ls -la "$work/out")
  "$facet" build "$@" 2>"$work/err" >/dev/null || got=$?
  [ "$got" = 2 ] || fail "build $*: exit $got, expected 2 ($(cat "$work/err"))"
  [ "$(wc -l <"$work/err")" = 1 ] || fail "build $*: expected one line on stderr: $(cat "$work/err")"
  grep -q -e "$pattern" "$work/err" || fail "build $*: stderr '$(cat "$work/err")' does not match '$pattern'"
  [ "$(ls -la "$work/out")" = "$before" ] || fail "build $*: changed $work/out: $(ls -la "$work/out")"
  echo "ok ($got): $(cat "$work/err")" | cut -c1-160
}
keep() { rm -rf "$work/out" && mkdir "$work/out"; }
keep && mkfifo "$work/out/pipe.o"
expect_kept "facet: error: .*/out/pipe.o is a FIFO, not a regular file; facet build writes its outputs only to new paths or regular files" "$gold" -o "$work/out/pipe.o"
[ -p "$work/out/pipe.o" ] || fail "the FIFO output is no longer a FIFO"
expect_kept "out/pipe.o is a FIFO" "$gold" -o "$o" --header "$work/out/pipe.o"
keep && ln -s /dev/null "$work/out/null.o"
expect_kept "facet: error: .*/out/null.o is a symbolic link, not a regular file" "$gold" -o "$work/out/null.o" --header "$h"
[ -L "$work/out/null.o" ] && [ "$(readlink "$work/out/null.o")" = /dev/null ] || fail "the symlink to /dev/null was replaced"
keep && mkdir "$work/out/dir.o" && ln -s dir.o "$work/out/dirlink.o"
expect_kept "facet: error: .*/out/dir.o is a directory, not a regular file" "$gold" -o "$work/out/dir.o"
expect_kept "facet: error: .*/out/dirlink.o is a symbolic link, not a regular file" "$gold" -o "$work/out/dirlink.o"
keep && cp "$gold" "$work/out/in.mat" && ln "$work/out/in.mat" "$work/out/hard.o"
expect_kept "facet: error: .*/out/in.mat is the same file as the material file .*/out/in.mat" "$work/out/in.mat" -o "$work/out/in.mat"
expect_kept "out/hard.o is the same file as the material file" "$work/out/in.mat" -o "$work/out/hard.o"
expect_kept "out/in.mat is the same file as the material file" "$work/out/in.mat" -o "$o" --header "$work/out/in.mat"
cmp -s "$gold" "$work/out/in.mat" || fail "the material file was changed"
# Outputs that do not exist yet: the same path spelled two ways.
cd "$work/out"
expect_kept "facet: error: ./x.o is the same file as the header x.o" "$gold" -o ./x.o --header x.o
expect_kept "facet: error: x.h is the same file as the header .*/out/../out/x.h" "$gold" -o x.h --header "$work/out/../out/x.h"
cd - >/dev/null
keep

# A failed build leaves an existing output as it was.
echo previous >"$work/keep.o"
"$facet" build "$gold" --target nowhere -o "$work/keep.o" 2>/dev/null && fail "unknown target accepted"
[ "$(cat "$work/keep.o")" = previous ] || fail "a failed build changed an existing output"
[ -z "$(ls "$work" | grep tmp)" ] || fail "temporary files left: $(ls "$work")"

# The inspection outputs.
"$facet" build "$gold" --emit llvm-ir -o "$work/g.ll"
grep -q '^define i64 @gold_eval_batch(' "$work/g.ll" || fail "llvm-ir lacks gold_eval_batch"
grep -q '^define internal i64 @gold_batch(' "$work/g.ll" || fail "llvm-ir: the kernel is not internal"
"$facet" build "$gold" --emit bitcode -o "$work/g.bc"
[ "$(head -c 2 "$work/g.bc")" = BC ] || fail "bitcode does not start with BC"
"$facet" build "$gold" --target aarch64-linux-gnu --emit asm -o "$work/g.s"
grep -q 'gold_eval_batch:' "$work/g.s" && grep -q -E 'fmul[[:space:]]+v[0-9]+\.4s' "$work/g.s" ||
  fail "aarch64 assembly lacks gold_eval_batch or 4-lane NEON arithmetic"

# The header: plain C99 and C++, slots documented, bound inputs are not slots.
"$facet" build "$source/materials/plastic.mat" --set roughness=0.3 --prefix red -o "$work/red.o" --header "$work/red.h"
grep -q '#define red_INPUT_COUNT 3' "$work/red.h" || fail "red.h: plastic with roughness bound has 3 slots"
grep -q '#define red_SLOT_albedo_g 1' "$work/red.h" || fail "red.h: albedo.g is slot 1"
grep -q 'options   backend=simd;math=exact;width=[0-9]*;set.roughness=0.3' "$work/red.h" || fail "red.h: options not recorded"
grep -q 'hash      sha256 [0-9a-f]\{64\}' "$work/red.h" || fail "red.h: no material hash"
grep -q 'Facet [0-9]' "$work/red.h" || fail "red.h: no Facet version"
printf '#include "red.h"\nint main(void) { float n[3] = {0, 0, 1}, rgb[3]; red_eval(n, n, 0, rgb); return rgb[0] > 0 ? 0 : 1; }\n' >"$work/use.c"
cc -std=c99 -pedantic -Wall -Wextra -Werror -I"$work" "$work/use.c" "$work/red.o" -lm -o "$work/use" && "$work/use" ||
  fail "red.h/red.o: a C99 program does not compile, link or evaluate"
c++ -x c++ -std=c++17 -Wall -Werror -fsyntax-only -I"$work" "$work/use.c" || fail "red.h is not valid C++"

# Macros keep the prefix's and the inputs' case: prefixes Clash and clash and
# inputs roughness and Roughness give distinct macros and include guards; an
# rgb tint's tint.r beside a float tint_r would share one, which is refused.
cat >"$work/clash.mat" <<'EOF'
material Clash {
    input roughness = 0.3 in 0 .. 1;
    input Roughness = 0.5 in 0 .. 1;
    ndf = ggx(roughness * Roughness);
}
material clash {
    input tint = rgb(0.5, 0.6, 0.7);
    input alpha = 0.2 in 0.01 .. 1;
    ndf = ggx(alpha);
    diffuse = lambert(tint);
}
material tinted {
    input tint = rgb(1, 1, 1);
    input tint_r = 0.5 in 0.01 .. 1;
    ndf = ggx(tint_r);
    diffuse = lambert(tint);
}
EOF
"$facet" build "$work/clash.mat" --material Clash -o "$work/Clash.o" --header "$work/Clash.h"
"$facet" build "$work/clash.mat" --material clash -o "$work/clash.o" --header "$work/clash.h"
cat >"$work/clash.c" <<'EOF'
#include "Clash.h"
#include "clash.h"
#include <stdio.h>
int main(void) {
    float n[3] = {0, 0, 1}, a[3], b[3];
    Clash_eval(n, n, NULL, a);
    clash_eval(n, n, NULL, b);
    printf("%d %d %d %d %d %d %d %d\n", Clash_INPUT_COUNT, Clash_SLOT_roughness, Clash_SLOT_Roughness, clash_INPUT_COUNT,
           clash_SLOT_tint_r, clash_SLOT_tint_g, clash_SLOT_tint_b, clash_SLOT_alpha);
    return Clash_HAS_SAMPLER == 1 && clash_HAS_SAMPLER == 1 && a[0] > 0 && b[0] > 0 ? 0 : 1;
}
EOF
if cc -std=c99 -pedantic -Wall -Wextra -Werror -I"$work" "$work/clash.c" "$work/Clash.o" "$work/clash.o" -lm -o "$work/clash"; then
  got=$("$work/clash") || fail "Clash and clash: an eval gave 0 or a header says no sampler"
  [ "$got" = "2 0 1 4 0 1 2 3" ] || fail "Clash and clash: macros are '$got', expected '2 0 1 4 0 1 2 3'"
else
  fail "Clash.h and clash.h together do not compile"
fi
expect 2 "facet: error: inputs 'tint' (slot tint.r) and 'tint_r' (slot tint_r) would both be the header's macro tinted_SLOT_tint_r" \
  "$work/clash.mat" --material tinted -o "$o" --header "$h"
"$facet" build "$work/clash.mat" --material tinted --set tint_r=0.3 -o "$work/tinted.o" --header "$work/tinted.h" ||
  fail "tinted with tint_r bound (no clash left) failed"
grep -q '^#define tinted_SLOT_tint_b 2$' "$work/tinted.h" || fail "tinted.h: tint.b is not slot 2"

# User text copied into the header's comment cannot end the comment or break
# a line: a path with "*/" in it, one with a newline, tab, "??/" and UTF-8.
inject="$work/x*/ int injected = 42; /*"
odd="$work/nl"$'\n'" int injected = 42; é"$'\t'"??/"
for dir in "$inject" "$odd"; do
  mkdir -p "$dir"
  cp "$gold" "$dir/gold.mat"
  (cd "$dir" && "$facet" build "$dir/gold.mat" -o g.o --header g.h) || fail "build from '$dir' failed"
  cc -std=c99 -Wall -Werror -fsyntax-only "$dir/g.h" || fail "the header built in '$dir' is not clean C99"
  # -P: no line markers, which name the file (and so the path) outside any comment.
  [ "$(cc -E -P "$dir/g.h" | grep -c 'injected = 42')" = 0 ] || fail "the path '$dir' escaped the header's comment"
  # Every line of the leading comment is still one: "/*" or " *" first.
  [ "$(awk 'NR == 1, /^ \*\/$/' "$dir/g.h" | grep -c -v -E '^(/\*| \*)')" = 0 ] ||
    fail "the path '$dir' broke a line of the header's comment"
done
grep -q -F '/x* / int injected = 42; / * /gold.mat' "$inject/g.h" || fail "the '*/' path is not in the header as 'x* /'"
grep -q -F '/nl\n int injected = 42; \xc3\xa9\t?\x3f//gold.mat' "$odd/g.h" || fail "the newline path is not escaped in the header"
exit $failed
