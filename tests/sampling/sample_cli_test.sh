#!/usr/bin/env bash
# sample_cli_test.sh: end-to-end tests of `facet sample` (SPEC section 5):
# the CSV contract (header, one row per sample, unit wi, weight 0 below the
# horizon), seeds, the usage errors and exit codes, and two properties
# checked in awk, independently of Facet:
#   - a Smith-masked GGX lobe with F = 1 sampled through visible normals
#     has weight = G2 / G1 <= 1 on every row;
#   - a Lambert base of albedo 1 with F = 0 (dielectric(1)) has a mean
#     weight of 1 (its directional albedo): the sampler is unbiased.
#
#   usage: sample_cli_test.sh PATH/TO/facet
set -u

FACET=${1:?usage: sample_cli_test.sh PATH/TO/facet}
case "$FACET" in /*) ;; *) FACET="$PWD/$FACET" ;; esac
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/../cli_expect.sh"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
export FACET_CACHE_DIR="$tmp/cache"

expect_contains() {  # TEXT NEEDLE WHAT
    checks=$((checks + 1))
    case "$1" in *"$2"*) ;; *) fail "$3: '$2' not in: $1" ;; esac
}
# awk_ok FILE PROGRAM WHAT: the awk program prints "ok" for the CSV.
awk_ok() {
    checks=$((checks + 1))
    local verdict
    verdict=$(awk -F, "$2" "$1")
    [ "$verdict" == "ok" ] || fail "$3: $verdict"
}

cat >ggx.mat <<'MAT'
material ggx_lobe {
    ndf = ggx(alpha_x = 0.3, alpha_y = 0.1);
    masking = smith_height_correlated;
}
MAT
cat >white.mat <<'MAT'
material white {
    ndf = beckmann(0.4);
    masking = cook_torrance;
    fresnel = dielectric(1);
    diffuse = lambert(1);
}
MAT
printf 'material broken {\n    ndf = ggx(;\n}\n' >broken.mat

# The CSV contract.
run "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n 3000 --out s.csv --seed 7
expect_rc 0 "sample ggx"
expect_contains "$out" "3000 samples of material ggx_lobe" "summary line"
checks=$((checks + 1))
[ "$(head -n 1 s.csv)" == "wi_x,wi_y,wi_z,pdf,weight_r,weight_g,weight_b" ] || fail "header: $(head -n 1 s.csv)"
checks=$((checks + 1))
[ "$(wc -l <s.csv)" -eq 3001 ] || fail "rows: $(wc -l <s.csv), expected 3001"
# (The default backend is the SIMD kernel's sampler: float results.)
awk_ok s.csv 'NR > 1 {
    len = sqrt($1 * $1 + $2 * $2 + $3 * $3)
    if (len < 1 - 1e-6 || len > 1 + 1e-6) { print "row " NR - 1 ": |wi| = " len; bad = 1; exit }
    if (!($4 > 0)) { print "row " NR - 1 ": pdf " $4; bad = 1; exit }
    if ($3 <= 0 && ($5 != 0 || $6 != 0 || $7 != 0)) { print "row " NR - 1 ": weight below the horizon"; bad = 1; exit }
    if ($5 > 1 + 1e-5 || $5 < 0) { print "row " NR - 1 ": weight " $5 " outside [0, 1]"; bad = 1; exit }
    if ($5 != $6 || $5 != $7) { print "row " NR - 1 ": F = 1 but the channels differ"; bad = 1; exit }
} END { if (!bad) print "ok" }' "wi unit, pdf > 0, G2/G1 weights in [0, 1]"

# Seeds: the same seed gives the same file, another seed another.
run "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n 3000 --out s2.csv --seed 7
expect_rc 0 "same seed"
checks=$((checks + 1))
cmp -s s.csv s2.csv || fail "the same seed gave different samples"
run "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n 3000 --out s3.csv --seed 8
checks=$((checks + 1))
cmp -s s.csv s3.csv && fail "seeds 7 and 8 gave the same samples"

# Standard output when --out is not given: the CSV only.
run "$FACET" sample ggx.mat --wo 0,0,1 -n 5
expect_rc 0 "sample to stdout"
checks=$((checks + 1))
[ "$(printf '%s\n' "$out" | wc -l)" -eq 6 ] || fail "stdout rows: $out"

# Unbiased: albedo-1 Lambert base, F = 0: the mean weight is 1.
run "$FACET" sample white.mat --wo 0,0.5,0.8660254037844386 -n 20000 --out w.csv --seed 3
expect_rc 0 "sample white"
awk_ok w.csv 'NR > 1 { s += $5; n++ } END {
    m = s / n
    if (m > 0.98 && m < 1.02) print "ok"; else print "mean weight " m ", expected 1 within 0.02" }' "white furnace"

# The compiled samplers (scalar, SIMD, fast) are unbiased too, and the
# reference (--backend interp) writes doubles.
for backend in "scalar" "simd --math fast"; do
    run "$FACET" sample white.mat --wo 0,0.5,0.8660254037844386 -n 20000 --out wj.csv --seed 3 --backend $backend
    expect_rc 0 "sample white --backend $backend"
    awk_ok wj.csv 'NR > 1 { s += $5; n++ } END {
        m = s / n
        if (m > 0.98 && m < 1.02) print "ok"; else print "mean weight " m ", expected 1 within 0.02" }' \
        "white furnace --backend $backend"
done
run "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n 2 --backend interp
expect_rc 0 "sample --backend interp"
run "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n 2 --backend gpu
expect_rc 2 "unknown backend"
expect_contains "$err" "--backend 'gpu' is not interp, scalar or simd" "unknown backend message"

# Usage errors (exit 2) and material errors (exit 65).
run "$FACET" sample ggx.mat -n 10
expect_rc 2 "no --wo"
expect_contains "$err" "facet: sample: --wo X,Y,Z is required" "no --wo message"
run "$FACET" sample ggx.mat --wo 0,1
expect_rc 2 "two components"
expect_contains "$err" "--wo expects X,Y,Z (three finite numbers), got '0,1'" "two components message"
run "$FACET" sample ggx.mat --wo 0,0,nan
expect_rc 2 "nan component"
run "$FACET" sample ggx.mat --wo 0,0,2
expect_rc 2 "not unit"
expect_contains "$err" "--wo 0,0,2 has length 2; it must be a unit vector" "not unit message"
run "$FACET" sample ggx.mat --wo 0,0.6,-0.8
expect_rc 2 "below the surface"
expect_contains "$err" "points into the surface" "below the surface message"
# A lobe that scatters below the surface is seen from either side: wo
# inside draws directions on both sides (refracted out, reflected in), each
# row's wi a unit vector; wo in the surface plane is refused.
cat >glass.mat <<'MAT'
material glass {
    ndf = ggx(0.3);
    masking = smith_height_correlated;
    fresnel = dielectric(1.5);
    scatter = both;
}
MAT
run "$FACET" sample glass.mat --wo 0,0.6,-0.8 -n 4000 --backend interp --out "$tmp/glass.csv"
expect_rc 0 "glass from inside"
awk_ok "$tmp/glass.csv" 'NR > 1 && $4 > 0 { n++; up += ($3 > 0); down += ($3 < 0)
    l = $1 * $1 + $2 * $2 + $3 * $3; if (l < 0.999999 || l > 1.000001) bad++ }
    END { print (n > 3000 && up > 1000 && down > 100 && !bad) ? "ok" : "n " n " up " up " down " down " bad " bad }' \
    "glass samples on both sides"
run "$FACET" sample glass.mat --wo 1,0,0 --backend interp
expect_rc 2 "glass wo in the surface"
expect_contains "$err" "lies in the surface (z = 0): material 'glass' scatters on both sides" "in the surface message"
run "$FACET" sample ggx.mat --wo 0,0,1 -n 0
expect_rc 2 "-n 0"
expect_contains "$err" "-n expects a whole number" "-n 0 message"
run "$FACET" sample ggx.mat --wo 0,0,1 --seed -3
expect_rc 2 "negative seed"
run "$FACET" sample ggx.mat --wo 0,0,1 --bogus
expect_rc 2 "unknown option"
run "$FACET" sample ggx.mat --wo 0,0,1 --material nope
expect_rc 2 "unknown material"
expect_contains "$err" "no material named 'nope'" "unknown material message"
run "$FACET" sample broken.mat --wo 0,0,1
expect_rc 65 "broken material"
expect_contains "$err" "broken.mat:2:" "diagnostic location"
run "$FACET" sample ggx.mat --wo 0,0,1 --out "$tmp/no/such/dir/s.csv"
expect_rc 1 "unwritable --out"
expect_contains "$err" "cannot write" "unwritable message"

# A seed beyond 2^64 - 1 is an error, never saturated to 2^64 - 1.
run "$FACET" sample ggx.mat --wo 0,0,1 -n 2 --seed 99999999999999999999999
expect_rc 2 "seed beyond 2^64 - 1"
expect_contains "$err" "--seed expects a whole number from 0 to 2^64 - 1 = 18446744073709551615" "seed range message"
run "$FACET" sample ggx.mat --wo 0,0,1 -n 2 --seed 18446744073709551615
expect_rc 0 "seed 2^64 - 1"

# The output never goes over the material file (here through another name).
cp ggx.mat keep.mat
run "$FACET" sample keep.mat --wo 0,0,1 -n 2 --out ./keep.mat
expect_rc 2 "--out is the material file"
expect_contains "$err" "./keep.mat is the same file as the material file keep.mat" "same-file message"
cmp -s ggx.mat keep.mat || fail "the material file was changed"

# Samples are written as they are drawn: the memory of a run does not grow
# with N (a million samples once took ~140 bytes each). The peak resident
# size of 3,000,000 samples against 3,000 (same process, same kernel),
# read by python3's resource module.
peak() {
    python3 -c 'import resource, subprocess, sys
subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, check=True)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)' "$FACET" sample ggx.mat --wo 0.6,0,0.8 -n "$1" --out /dev/null
}
small=$(peak 3000) big=$(peak 3000000)
checks=$((checks + 1))
[ -n "$small" ] && [ -n "$big" ] && [ "$big" -lt $((small + 100000)) ] ||
    fail "3,000,000 samples peaked at ${big} KiB against ${small} KiB for 3,000 (the samples are held in memory)"
[ -c /dev/null ] || fail "/dev/null is no longer a character device"

echo "$checks checks, $failures failures"
[ "$failures" -eq 0 ]
