#!/usr/bin/env bash
# A fuzz of `facet build`'s target, CPU, feature and output arguments: every
# target this LLVM registers (bare and as ARCH-linux-gnu), a fixed-seed
# sample of the x86_64 and aarch64 CPUs, + and - of 20 features that matter
# to the kernels or the calling convention, and outputs of every file type.
# Each case must exit 0, 2 or 65 (never a signal, an LLVM abort, exit 1 or
# an internal error), with one stderr line where it fails with 2; outputs
# that are not new paths or regular files stay as they were; and the x86_64
# objects this host can run (its CPU less some features, or tuning flags)
# link with aot_run.c, pass its convention checks and match the double
# interpreter (five of them). Prints one summary line. The long tier's
# ctest aot_fuzz, with the suite's table cache: about two minutes on two cores.
set -euo pipefail
build=$1 source=$2
facet=$build/bin/facet reference=$build/tests/aot/facet_aot_reference
cc=${CC:-cc}
export FACET_CACHE_DIR=${FACET_CACHE_DIR-$build/tests/aot/fuzz-cache}
gold=$source/materials/gold.mat
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0 cases=0 linked=0 last=0
declare -A codes=()
runnable=()  # objects built for this host's CPU that it can run: "NAME|args" ($work/NAME.o, .h)
fail() { echo "FAIL: $*"; failed=1; }

# attempt ARGS...: one `facet build` of gold with ARGS, its exit code checked.
attempt() {
  local got=0
  timeout 120 "$facet" build "$gold" "$@" >/dev/null 2>"$work/err" || got=$?
  cases=$((cases + 1)) last=$got
  codes[$got]=$((${codes[$got]:-0} + 1))
  case $got in
    0 | 65) ;;
    2) [ "$(wc -l <"$work/err")" = 1 ] && grep -q '^facet: ' "$work/err" ||
         fail "build $*: exit 2 without one 'facet: ' line: $(head -c 300 "$work/err")" ;;
    *) fail "build $*: exit $got: $(head -c 300 "$work/err")" ;;
  esac
  return 0
}
# The names listed by an error message: "(PREFIX a, b, c)" or "PREFIX a, b; ...".
listed() { sed -n "s/.*$1 \([^;)]*\)[;)].*/\1/p" "$work/err" | tr -d ','; }

# Every registered target, bare and with an OS.
"$facet" build "$gold" --target nowhere -o "$work/t.o" 2>"$work/err" || true
targets=$(listed 'this LLVM has:')
[ "$(wc -w <<<"$targets")" -gt 10 ] || fail "no target list in: $(cat "$work/err")"
for t in $targets; do
  attempt --target "$t" -o "$work/t.o"
  attempt --target "$t-linux-gnu" -o "$work/t.o"
done

# A fixed-seed sample of each architecture's CPUs (every one would take
# minutes here).
for arch in x86_64:14 aarch64:8; do
  "$facet" build "$gold" --target "${arch%%:*}-linux-gnu" --cpu nowhere -o "$work/t.o" 2>"$work/err" || true
  cpus=$(listed 'CPUs:')
  [ "$(wc -w <<<"$cpus")" -gt 10 ] || fail "no CPU list for ${arch%%:*} in: $(cat "$work/err")"
  for cpu in $(tr ' ' '\n' <<<"$cpus" | shuf -n "${arch##*:}" --random-source=<(yes facet-fuzz)); do
    attempt --target "${arch%%:*}-linux-gnu" --cpu "$cpu" -o "$work/t.o"
  done
done
attempt --cpu native -o "$work/t.o"

# Features, + and -: x86_64 on this host's CPU where it is one, aarch64 generic.
host=""
[ "$(uname -m)" = x86_64 ] || host="--target x86_64-linux-gnu"
for f in x87 avx fma sse4.1 retpoline sse2 sse soft-float avx512f evex512 64bit-mode popcnt; do
  for sign in + -; do
    attempt $host --features "$sign$f" -o "$work/t.o" --header "$work/t.h"
    # Less of this CPU, or a code-generation flag: an object this host runs.
    if [ -z "$host" ] && [ "$last" = 0 ] && { [ $sign = - ] || [ $f = retpoline ]; }; then
      name=x86_$([ $sign = + ] && echo with || echo no)_${f//[.-]/_}
      mv "$work/t.o" "$work/$name.o" && mv "$work/t.h" "$work/$name.h"
      runnable+=("$name|--features $sign$f")
    fi
  done
done
for f in neon fp-armv8 strict-align sve fullfp16 reserve-x3 reserve-x18 v8.2a outline-atomics; do
  for sign in + -; do attempt --target aarch64-linux-gnu --features "$sign$f" -o "$work/t.o"; done
done

# Outputs of every file type: only a new path or a regular file is written.
out=$work/out
mkdir "$out" "$out/dir"
echo previous >"$out/file.o"
mkfifo "$out/fifo.o"
ln -s file.o "$out/link.o"
ln -s dir "$out/dirlink.o"
cp "$gold" "$out/in.mat"
gold_copy() { local g=$gold; gold=$out/in.mat; attempt "$@"; gold=$g; }
attempt -o "$out/file.o" --header "$out/file.h"
[ -f "$out/file.o" ] && [ ! -L "$out/file.o" ] && [ "$(head -c 4 "$out/file.o" | tail -c 3)" = ELF ] ||
  fail "a build over a regular file did not replace it with the object"
for bad in missing/x.o dir fifo.o link.o dirlink.o; do
  attempt -o "$out/$bad"
  attempt -o "$out/new.o" --header "$out/$bad"
done
gold_copy -o "$out/in.mat"
gold_copy -o "$out/new.o" --header "$out/in.mat"
attempt -o "$out/same.o" --header "$out/same.o"
attempt -o "$out/file.o" --header "$out/../out/file.o"
[ -p "$out/fifo.o" ] && [ -L "$out/link.o" ] && [ -L "$out/dirlink.o" ] && [ -d "$out/dir" ] ||
  fail "an output that is not a regular file was replaced: $(ls -l "$out")"
[ -z "$(ls -A "$out/dir")" ] && [ ! -e "$out/new.o" ] && [ ! -e "$out/same.o" ] || fail "a refused build wrote: $(ls -lR "$out")"
cmp -s "$gold" "$out/in.mat" || fail "the material file was overwritten"

# Objects this host can run: link, run (aot_run.c checks the conventions),
# and compare with the double interpreter.
if [ -z "$host" ] && [ -x "$reference" ]; then
  "$reference" inputs "$gold" gold "" 1000 "$work/lanes.in" >/dev/null
  # A handful: each check compiles a JIT kernel too.
  for entry in "${runnable[@]:0:5}"; do
    name=${entry%%|*} args=${entry#*|}
    "$cc" -std=c99 -O1 -DAOT_PREFIX=gold -include "$work/$name.h" "$source/tests/aot/aot_run.c" "$work/$name.o" -lm \
      -o "$work/$name.run" || { fail "$name ($args) does not link"; continue; }
    "$work/$name.run" "$work/lanes.in" "$work/$name.out" >/dev/null || { fail "$name ($args) failed to run"; continue; }
    "$reference" against-interpreter "$gold" gold "backend=simd;math=exact" 1000 "$work/$name.out" >"$work/ref" ||
      fail "$name ($args) against the interpreter: $(grep -m3 -i 'fail' "$work/ref")"
    linked=$((linked + 1))
  done
  [ $linked = 5 ] || fail "only $linked x86_64 objects linked and ran"
fi

summary=""
for code in $(printf '%s\n' "${!codes[@]}" | sort -n); do summary+=" exit $code: ${codes[$code]},"; done
echo "aot fuzz: $cases cases,${summary} $linked objects linked, run and checked"
exit $failed
