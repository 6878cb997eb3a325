#!/usr/bin/env bash
# stress_test.sh: the front end's stress materials on every backend
# (scripts/stress-materials.sh measures their time and memory). Accepted
# input never crashes a backend, and what would make LLVM take minutes or
# overflow its stack is refused by the checker with a message at the
# statement that passes the compute budget (compiler/frontend/ComputeCost.h):
#   - 10000 unused inputs: accepted; every backend evaluates the material as
#     if they were not there (the inputs are never loaded);
#   - a 100000-let chain and a 20000-let rgb mix chain: refused (exit 65);
#   - a 3900-let chain, near the budget: accepted on every backend, and the
#     kernels agree with the interpreter.
#
#   usage: stress_test.sh PATH/TO/facet
set -u
FACET=${1:?usage: stress_test.sh PATH/TO/facet}
case "$FACET" in /*) ;; *) FACET="$PWD/$FACET" ;; esac
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/../cli_expect.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

python3 - <<'PY'
def unused(n):
    return ("material unused {\n" + "".join(f"    input u{i} = 0.5 in 0 .. 1;\n" for i in range(n)) +
            "    ndf = ggx(0.3);\n    masking = smith_height_correlated;\n    fresnel = schlick(0.04);\n}\n")
def chain(n):
    s = "material chain {\n    input r = 0.5 in 0 .. 1;\n    let a0 = r;\n"
    s += "".join(f"    let a{i} = a{i - 1} + 0.000001;\n" for i in range(1, n))
    return s + f"    ndf = ggx(clamp(a{n - 1}, 0.01, 1));\n    masking = smith_height_correlated;\n}}\n"
def mix(n):
    s = "material mixchain {\n    input t = 0.5 in 0 .. 1;\n    input c = rgb(0.2, 0.3, 0.4);\n    let m0 = c;\n"
    s += "".join(f"    let m{i} = mix(m{i - 1}, rgb(0.5, 0.5, 0.5), t);\n" for i in range(1, n))
    return s + f"    ndf = ggx(0.3);\n    diffuse = lambert(m{n - 1});\n}}\n"
for name, text in [("unused10k", unused(10000)), ("chain100k", chain(100000)), ("mix20k", mix(20000)),
                   ("chain3900", chain(3900))]:
    open(name + ".mat", "w").write(text)
open("plain.mat", "w").write(unused(0).replace("material unused", "material plain"))
PY
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n0,0,1,0.6,0,0.8\n0.6,0,0.8,0,0,1\n0.28,0.96,0,0,0,1\n' >dirs.csv

run "$FACET" check chain100k.mat
expect_rc 65 "a 100000-let chain"
expect_first_line "$err" "chain100k.mat:3984:9: error: material 'chain' computes too much to compile: at let 'a3981' its inputs, lets and model arguments already cost more than 4000 float operations (an rgb value counts three, exp and log 100 each, pow 200, each input read 20); simplify its expressions" \
    "a 100000-let chain: message"
run "$FACET" eval mix20k.mat --backend simd --in dirs.csv
expect_rc 65 "a 20000-let rgb mix chain on the simd backend"
expect_first_line "$err" "mix20k.mat:440:9: error: material 'mixchain' computes too much to compile: at let 'm436' its inputs, lets and model arguments already cost more than 4000 float operations (an rgb value counts three, exp and log 100 each, pow 200, each input read 20); simplify its expressions" \
    "a 20000-let mix chain: message"

run "$FACET" eval plain.mat --in dirs.csv --out plain.csv
expect_rc 0 "the same material without inputs"
for m in unused10k chain3900; do
    run "$FACET" eval "$m.mat" --in dirs.csv --out "$m-interp.csv"
    expect_rc 0 "$m on the interpreter"
    for backend in scalar simd; do
        run timeout 120 "$FACET" eval "$m.mat" --backend "$backend" --in dirs.csv --out "$m-$backend.csv"
        expect_rc 0 "$m on the $backend backend"
        # float kernels against the double interpreter: 1e-6 relative
        verdict=$(paste -d, "$m-interp.csv" "$m-$backend.csv" | awk -F, 'NR > 1 {
            for (c = 1; c <= 3; ++c) { d = $c - $(c + 3); if (d < 0) d = -d; s = $c < 0 ? -$c : $c
                if (d > 1e-6 * s + 1e-30) { print "row " NR - 1 ": " $c " against " $(c + 3); exit } } }
            END { }')
        expect_eq "$verdict" "" "$m: $backend agrees with the interpreter"
    done
done
# An object file of the material with 10000 unused inputs: its entry points
# pass on only the slots the kernels read, so it builds in seconds.
run timeout 300 "$FACET" build unused10k.mat -o unused10k.o --header unused10k.h
expect_rc 0 "an object file of 10000 unused inputs"

# The unused inputs change nothing: the same values as without them.
expect_eq "$(cat unused10k-interp.csv)" "$(cat plain.csv)" "10000 unused inputs: the interpreter's values"
expect_eq "$(cat unused10k-simd.csv)" "$(FACET_CACHE_DIR=$tmp/cache "$FACET" eval plain.mat --backend simd --in dirs.csv)" \
    "10000 unused inputs: the simd kernel's values"

echo "stress_test: $checks checks, $failures failed"
[ "$failures" -eq 0 ]
