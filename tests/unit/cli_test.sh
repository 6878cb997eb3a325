#!/usr/bin/env bash
# cli_test.sh: end-to-end tests of the `facet` command line (SPEC section 5).
#
#   usage: cli_test.sh PATH/TO/facet
#
# Why a separate test: the exit codes (0 ok, 1 a check failed, 2 usage,
# 65 a material file error), the exact diagnostic text and the CSV contract
# (one output row per input row, bad rows reported by number and zeroed,
# good rows still evaluated) are what scripts and build systems depend on,
# and none of it is visible from the C++ API.
#
# Expected BRDF values are worked out by hand for one material:
#   ndf = ggx(alpha), masking none, fresnel = schlick(f0 = 0.04), lambert(albedo)
#   wi = wo = n:            D = 1/(pi a^2), F = f0, G = 1, f = F D / 4 + albedo/pi
#                           a = 0.5: (0.04 + albedo)/pi;  a = 1: (0.01 + albedo)/pi
#   mirror pair at 60 deg:  h = n, F = f0 + (1 - f0)/2^5 = 0.07, 4 cos^2 = 1,
#                           a = 0.5: f = 0.07 * 4/pi + albedo/pi = (0.28 + albedo)/pi
# and computed again here in awk, independently of Facet.
set -u

FACET=${1:?usage: cli_test.sh PATH/TO/facet}
case "$FACET" in /*) ;; *) FACET="$PWD/$FACET" ;; esac
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/../cli_expect.sh"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

expect_first_line() {  # TEXT EXPECTED-FIRST-LINE WHAT
    expect_eq "$(printf '%s\n' "$1" | head -n 1)" "$2" "$3"
}
# near_row FILE ROW EXPR_R EXPR_G EXPR_B: data row ROW (1-based, after the
# header) of a CSV holds the three awk expressions (pi is defined) to 1e-14.
near_row() {
    checks=$((checks + 1))
    local verdict
    verdict=$(awk -F, -v row="$2" "
        BEGIN { pi = atan2(0, -1) }
        NR == row + 1 {
            e[1] = ($3); e[2] = ($4); e[3] = ($5)
            for (i = 1; i <= 3; ++i) {
                d = \$i - e[i]; if (d < 0) d = -d
                s = e[i] < 0 ? -e[i] : e[i]
                if (d > 1e-14 * s + 1e-300) { printf \"channel %d: got %s, expected %.17g\", i, \$i, e[i]; exit }
            }
            print \"ok\"; exit
        }
        END { }" "$1")
    [ "$verdict" == "ok" ] || fail "$1 row $2: ${verdict:-no such row}"
}
expect_zero_row() {  # FILE ROW
    checks=$((checks + 1))
    local line
    line=$(sed -n "$(($2 + 1))p" "$1")
    [ "$line" == "0,0,0" ] || fail "$1 row $2: expected 0,0,0, got '$line'"
}

# ---- inputs ------------------------------------------------------------------
cat >test.mat <<'EOF'
// Two materials: the CLI picks the first unless --material says otherwise.
material test {
    input alpha = 0.5 in 0.01 .. 1;
    input albedo = rgb(0.2, 0.4, 0.6);
    ndf = ggx(alpha);
    fresnel = schlick(f0 = 0.04);
    diffuse = lambert(albedo);
}
material other {
    ndf = beckmann(0.25);
}
EOF

cat >bad.mat <<'EOF'
material bad {
    input roughness = 0.5 in 0 .. 1;
    ndf = ggx(rougness);
    masking = smith_height_correlated;
    fresnel = schlik(0.04);
}
EOF
bad_diags="bad.mat:3:15: error: undefined name 'rougness' (did you mean 'roughness'?)
bad.mat:5:15: error: unknown fresnel model 'schlik' (did you mean 'schlick'?)"

S60=0.8660254037844386  # sin 60 deg, to 16 digits: a unit vector to 1e-16

# Rows 1, 5, 9, 10, 11 are good; 2, 3, 4, 6, 7, 8 are bad in six different ways.
cat >mixed.csv <<EOF
wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,alpha
0,0,1,0,0,1,0.5
0,0,1,0,0,1
0,0,1,0,0,abc,0.5
nan,0,1,0,0,1,0.5
$S60,0,0.5,-$S60,0,0.5,0.5
inf,0,1,0,0,1,0.5
0,0,2,0,0,1,0.5
0,0,1,0,0,1,nan
0,0,1,0,0,1,1
0.6,0,-0.8,0,0,1,0.5
0,0,1,0,0,1,5
EOF

cat >dirs.csv <<EOF
wi_x,wi_y,wi_z,wo_x,wo_y,wo_z
0,0,1,0,0,1
$S60,0,0.5,-$S60,0,0.5
EOF

# ---- facet check ---------------------------------------------------------------
run "$FACET" check test.mat
expect_rc 0 "check on a good file"
expect_eq "$out$err" "" "check on a good file prints nothing"

run "$FACET" check bad.mat
expect_rc 65 "check on a bad file"
expect_eq "$err" "$bad_diags" "check on a bad file: exact diagnostics"
expect_eq "$out" "" "check prints diagnostics on stderr only"

run "$FACET" check test.mat bad.mat
expect_rc 65 "check with one bad file of two"
expect_eq "$err" "$bad_diags" "check with one bad file of two: only its diagnostics"

run "$FACET" check missing.mat
expect_rc 65 "check on a missing file"
expect_eq "$err" "missing.mat: error: cannot open file" "check on a missing file: message"

run "$FACET" check
expect_rc 2 "check without files"
expect_first_line "$err" "facet: check: no files given" "check without files: message"

# ---- facet eval: good and bad rows -----------------------------------------------
run "$FACET" eval test.mat --in mixed.csv
cp stdout.txt mixed.out
expect_rc 1 "eval with bad rows"
expect_eq "$(wc -l <mixed.out | tr -d ' ')" "12" "eval: header plus one line per input row"
expect_first_line "$out" "r,g,b" "eval: output header"
expect_eq "$err" "mixed.csv:3: error: row 2: expected 7 columns, found 6; its output is 0,0,0
mixed.csv:4: error: row 3: column 'wo_z' is not a number: 'abc'; its output is 0,0,0
mixed.csv:5: error: row 4: column 'wi_x' is NaN; its output is 0,0,0
mixed.csv:7: error: row 6: column 'wi_x' is infinite; its output is 0,0,0
mixed.csv:8: error: row 7: wi is not a unit vector (length 2); its output is 0,0,0
mixed.csv:9: error: row 8: column 'alpha' is NaN; its output is 0,0,0
6 of 11 rows invalid" "eval: every bad row reported by number"
near_row mixed.out 1 "0.24/pi" "0.44/pi" "0.64/pi"        # normal incidence, a = 0.5
for r in 2 3 4 6 7 8; do expect_zero_row mixed.out $r; done
near_row mixed.out 5 "0.48/pi" "0.68/pi" "0.88/pi"        # mirror 60 deg, a = 0.5
near_row mixed.out 9 "0.21/pi" "0.41/pi" "0.61/pi"        # normal incidence, a = 1 (column)
expect_zero_row mixed.out 10                              # wi below the horizon: f = 0, a valid row
near_row mixed.out 11 "0.21/pi" "0.41/pi" "0.61/pi"       # a = 5 is clamped to the range top, 1

# Output precision: %.17g round-trips the double.
expect_eq "$(sed -n 2p mixed.out | cut -d, -f1)" "0.076394372684109757" "eval: full precision output"

# All rows good: exit 0.
run "$FACET" eval test.mat --in dirs.csv
expect_rc 0 "eval with only good rows"
echo "$out" >dirs.out
near_row dirs.out 1 "0.24/pi" "0.44/pi" "0.64/pi"
near_row dirs.out 2 "0.48/pi" "0.68/pi" "0.88/pi"

# Header only: no rows, exit 0.
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n' >empty_rows.csv
run "$FACET" eval test.mat --in empty_rows.csv
expect_rc 0 "eval with no data rows"
expect_eq "$out" "r,g,b" "eval with no data rows: header only"

# ---- --set ---------------------------------------------------------------------
run "$FACET" eval test.mat --set alpha=1 --in dirs.csv
expect_rc 0 "--set float"
echo "$out" >set1.out
near_row set1.out 1 "0.21/pi" "0.41/pi" "0.61/pi"
# mirror 60 deg with a = 1: 0.07 * (1/pi) / (4 * 0.25) = 0.07/pi
near_row set1.out 2 "0.27/pi" "0.47/pi" "0.67/pi"

run "$FACET" eval test.mat --set albedo=0,0.5,1 --in dirs.csv
expect_rc 0 "--set rgb r,g,b"
echo "$out" >set2.out
near_row set2.out 1 "0.04/pi" "0.54/pi" "1.04/pi"

run "$FACET" eval test.mat --set albedo=0.3 --set alpha=1 --in dirs.csv
expect_rc 0 "--set rgb with one value (all channels) and a float"
echo "$out" >set3.out
near_row set3.out 1 "0.31/pi" "0.31/pi" "0.31/pi"

run "$FACET" eval test.mat --set nope=1 --in dirs.csv
expect_rc 2 "--set of an unknown input"
expect_first_line "$err" "facet: --set: material 'test' has no input 'nope'" "--set of an unknown input: message"

run "$FACET" eval test.mat --set alpha=1,2,3 --in dirs.csv
expect_rc 2 "--set of three values for a float input"
expect_first_line "$err" "facet: --set alpha: input 'alpha' is float; give one value" "--set float arity: message"

run "$FACET" eval test.mat --set alpha=abc --in dirs.csv
expect_rc 2 "--set of a non-number"
expect_first_line "$err" "facet: --set alpha: 'abc' is not a finite number" "--set non-number: message"

run "$FACET" eval test.mat --set alpha=nan --in dirs.csv
expect_rc 2 "--set of NaN"

run "$FACET" eval test.mat --set albedo=1,2 --in dirs.csv
expect_rc 2 "--set of two values"

run "$FACET" eval test.mat --set alpha --in dirs.csv
expect_rc 2 "--set without '='"
expect_first_line "$err" "facet: --set expects NAME=VALUE, got 'alpha'" "--set without '=': message"

# ---- input columns ---------------------------------------------------------------
cat >channels.csv <<EOF
wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,albedo.g,alpha
0,0,1,0,0,1,0,0.5
0,0,1,0,0,1,1,1
EOF
run "$FACET" eval test.mat --in channels.csv
expect_rc 0 "a column per rgb channel (albedo.g)"
echo "$out" >channels.out
near_row channels.out 1 "0.24/pi" "0.04/pi" "0.64/pi"
near_row channels.out 2 "0.21/pi" "1.01/pi" "0.61/pi"

cat >whole.csv <<EOF
wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,albedo
0,0,1,0,0,1,0.1
EOF
run "$FACET" eval test.mat --in whole.csv
expect_rc 0 "an rgb input column sets all three channels"
echo "$out" >whole.out
near_row whole.out 1 "0.14/pi" "0.14/pi" "0.14/pi"

cat >unknown_col.csv <<EOF
wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,bogus
0,0,1,0,0,1,1
EOF
run "$FACET" eval test.mat --in unknown_col.csv
expect_rc 2 "unknown column"
expect_eq "$err" "unknown_col.csv:1: error: column 'bogus' is not an input of material 'test' (inputs: alpha, albedo)" \
    "unknown column: message"
expect_eq "$out" "" "unknown column: no output"

run "$FACET" eval test.mat --set alpha=1 --in mixed.csv
expect_rc 2 "a column for an input bound with --set"
expect_eq "$err" "mixed.csv:1: error: column 'alpha' sets input 'alpha', which is bound with --set" \
    "column bound with --set: message"

printf 'wi_x,wi_y,wi_z,wo_x,wo_y\n0,0,1,0,0\n' >no_woz.csv
run "$FACET" eval test.mat --in no_woz.csv
expect_rc 2 "missing direction column"
expect_eq "$err" "no_woz.csv:1: error: missing column 'wo_z' (the header needs wi_x,wi_y,wi_z,wo_x,wo_y,wo_z)" \
    "missing direction column: message"

: >empty.csv
run "$FACET" eval test.mat --in empty.csv
expect_rc 2 "empty CSV"

run "$FACET" eval test.mat --in does_not_exist.csv
expect_rc 2 "missing CSV"
expect_eq "$err" "does_not_exist.csv: error: cannot open file" "missing CSV: message"

# ---- --out, --material -------------------------------------------------------------
run "$FACET" eval test.mat --in mixed.csv --out written.csv
expect_rc 1 "--out with bad rows"
expect_eq "$out" "" "--out: nothing on stdout"
expect_eq "$(cat written.csv 2>/dev/null)" "$(cat mixed.out)" "--out: the file holds what stdout would"

run "$FACET" eval test.mat --in dirs.csv --out nodir/x.csv
expect_rc 2 "--out into a missing directory"

run "$FACET" eval test.mat --material other --in dirs.csv
expect_rc 0 "--material picks the second material"
echo "$out" >other.out
# Beckmann a = 0.25 at h = n: D = 1/(pi a^2) = 16/pi; f = D/4 (no F, no G, no diffuse).
near_row other.out 1 "4/pi" "4/pi" "4/pi"
# mirror 60 deg: D/(4 cos^2 60) = D.
near_row other.out 2 "16/pi" "16/pi" "16/pi"

run "$FACET" eval test.mat --material nope --in dirs.csv
expect_rc 2 "--material that does not exist"
expect_first_line "$err" "facet: eval: no material named 'nope' in test.mat (materials: test, other)" "--material nope: message"

run "$FACET" eval bad.mat --in dirs.csv
expect_rc 65 "eval of a bad material"
expect_eq "$err" "$bad_diags" "eval of a bad material: the same diagnostics as check"

# ---- no silent zeros: clamping in double, the kernel's own per-row status ----------
printf 'material rough {\n    input roughness = 0.4 in 0 .. 1;\n    ndf = ggx(roughness * roughness);\n    fresnel = schlick(f0 = 0.04);\n    diffuse = lambert(0.5);\n}\n' >rough.mat
# roughness = 1e39 is clamped to 1 in double (not converted to float first:
# that is Inf, an invalid lane): every backend gives the value of roughness 1.
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,roughness\n0,0,1,0,0,1,1e39\n0,0,1,0,0,1,1\n' >rough.csv
for backend in interp scalar simd; do
    run "$FACET" eval rough.mat --backend $backend --in rough.csv
    expect_rc 0 "roughness=1e39 clamped in double ($backend)"
    echo "$out" >rough.$backend.out
    expect_eq "$(sed -n 2p rough.$backend.out)" "$(sed -n 3p rough.$backend.out)" "1e39 is 1 ($backend)"
    run "$FACET" eval rough.mat --backend $backend --set roughness=1e39 --in dirs.csv
    expect_rc 0 "--set roughness=1e39 ($backend)"
    expect_eq "$(printf '%s\n' "$out" | sed -n 2p)" "$(sed -n 3p rough.$backend.out)" "--set 1e39 is 1 ($backend)"
done
near_row rough.interp.out 1 "0.01/pi + 0.5/pi" "0.01/pi + 0.5/pi" "0.01/pi + 0.5/pi"
# A grazing pair whose BRDF (about 5e40) float cannot hold: the compiled
# kernels' status marks the row; its number and the reason go to stderr, exit 1.
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n0,0,1,0,0,1\n1,0,1e-40,-1,0,1e-40\n' >grazing.csv
for backend in scalar simd; do
    run "$FACET" eval rough.mat --backend $backend --in grazing.csv
    expect_rc 1 "grazing row beyond float ($backend)"
    expect_eq "$err" "grazing.csv:3: error: row 2: the $backend kernel rejected it: a model parameter is not finite in float, or the result is beyond float range; its output is 0,0,0
1 of 2 rows invalid" "grazing row beyond float: reported ($backend)"
    echo "$out" >grazing.$backend.out
    expect_zero_row grazing.$backend.out 2
done
run "$FACET" eval rough.mat --backend interp --in grazing.csv
expect_rc 0 "grazing row in double (interp prints doubles)"
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,x\n0,0,1,0,0,1,1e39\n' >wide.csv
printf 'material wide { input x = 1; ndf = ggx(0.5); diffuse = lambert(min(x, 1)); }\n' >wide.mat
run "$FACET" eval wide.mat --backend simd --in wide.csv
expect_rc 1 "an unranged input beyond float on a float kernel"
expect_first_line "$err" "wide.csv:2: error: row 1: input 'x' = 1e+39 is beyond float range; its output is 0,0,0" \
    "an unranged input beyond float: message"

# ---- every write checked ------------------------------------------------------------
if [ -w /dev/full ]; then
    run "$FACET" eval test.mat --in dirs.csv --out /dev/full
    expect_rc 1 "eval --out /dev/full"
    expect_eq "$err" "facet: error: cannot write /dev/full: No space left on device" "eval --out /dev/full: message"
    "$FACET" eval test.mat --in dirs.csv >/dev/full 2>stderr.txt; rc=$?; err=$(cat stderr.txt)
    expect_rc 1 "eval >/dev/full"
    expect_eq "$err" "facet: error: cannot write standard output: No space left on device" "eval >/dev/full: message"
    "$FACET" ir test.mat >/dev/full 2>stderr.txt; rc=$?; err=$(cat stderr.txt)
    expect_rc 1 "ir >/dev/full"
    expect_eq "$err" "facet: error: cannot write standard output: No space left on device" "ir >/dev/full: message"
    "$FACET" --help >/dev/full 2>stderr.txt; rc=$?; err=$(cat stderr.txt)
    expect_rc 1 "--help >/dev/full"
    printf 'material k { ndf = ggx(0.5); masking = smith_height_correlated; energy = kulla_conty; }\n' >kc.mat
    run "$FACET" lut kc.mat -o /dev/full
    expect_rc 1 "lut -o /dev/full"
    expect_first_line "$err" "facet: lut: cannot write /dev/full: No space left on device" "lut -o /dev/full: message"
    ln -s /dev/full full.png
    run "$FACET" render test.mat -o full.png --size 16
    expect_rc 1 "render into /dev/full"
    expect_first_line "$err" "facet: render: cannot write full.png: No space left on device" "render into /dev/full: message"
fi
run "$FACET" render test.mat -o x.bmpx --size 16
expect_rc 1 "render -o with an unknown extension"
expect_first_line "$err" "facet: render: cannot write x.bmpx: OpenImageIO could not find a format writer for \"x.bmpx\". Is it a file format that OpenImageIO doesn't know about?" \
    "render -o x.bmpx: the reason"

# ---- messages ----------------------------------------------------------------------
printf '\xef\xbb\xbfwi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n0,0,1,0,0,1\n' >bom.csv
run "$FACET" eval test.mat --in bom.csv
expect_rc 0 "a CSV with a UTF-8 BOM"
printf '\xef\xbb\xbfmaterial m { ndf = ggx(0.5); }\n' >bom.mat
run "$FACET" check bom.mat
expect_rc 0 "a material file with a UTF-8 BOM"
printf 'material m {\r    ndf = ggx(0.5);\r    masking = nope;\r}\r' >cr.mat
run "$FACET" check cr.mat
expect_rc 65 "CR-only line endings"
expect_first_line "$err" "cr.mat:3:15: error: unknown masking model 'nope' (did you mean 'none'?)" "CR-only line endings: the line is counted"
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\r0,0,1,0,0,1\r0,0,2,0,0,1\r' >cr.csv
run "$FACET" eval test.mat --in cr.csv
expect_rc 1 "CSV with CR-only line endings"
expect_first_line "$err" "cr.csv:3: error: row 2: wi is not a unit vector (length 2); its output is 0,0,0" \
    "CSV with CR-only line endings: the line is counted"
mkdir -p adir.mat
run "$FACET" check adir.mat
expect_rc 65 "a directory as material file"
expect_eq "$err" "adir.mat: error: is a directory, not a file" "a directory as material file: message"
mkfifo fifo.mat
run timeout 20 "$FACET" check fifo.mat
expect_rc 65 "a FIFO nobody writes to as material file (no hang)"
expect_first_line "$err" "fifo.mat: error: is a FIFO (named pipe) and nothing was written to it" \
    "a FIFO nobody writes to: message"
run "$FACET" check <(cat test.mat)
expect_rc 0 "a pipe as material file"
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,wi_x\n0,0,1,0,0,1,0\n' >dupcol.csv
run "$FACET" eval test.mat --in dupcol.csv
expect_rc 2 "a duplicated CSV column"
expect_eq "$err" "dupcol.csv:1: error: column 'wi_x' appears twice (columns 1 and 7)" "a duplicated CSV column: message"
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,albedo,albedo.g\n0,0,1,0,0,1,0.1,0.2\n' >dupinput.csv
run "$FACET" eval test.mat --in dupinput.csv
expect_rc 2 "two columns setting one input"
expect_eq "$err" "dupinput.csv:1: error: columns 'albedo' and 'albedo.g' both set 'albedo.g'" "two columns setting one input: message"
run "$FACET" eval test.mat --set alpha=0.5 --set alpha=1 --in dirs.csv
expect_rc 2 "a repeated --set"
expect_first_line "$err" "facet: --set alpha: given twice" "a repeated --set: message"
run "$FACET" ir test.mat --set nosuch=1
expect_rc 2 "ir --set of an unknown input: the same exit code as eval"
expect_first_line "$err" "facet: --set: material 'test' has no input 'nosuch'" "ir --set nosuch: message"
# ir --plan: the lowering plan of the material, one decision per line.
run "$FACET" ir test.mat --simd --plan
expect_rc 0 "ir --plan"
expect_eq "$(printf '%s\n' "$out" | grep -E '^(batch-bodies|smith-lambda):')" \
    "batch-bodies: float-first"$'\n'"smith-lambda: none" "ir --plan: the decisions"
expect_eq "$(printf '%s\n' "$out" | grep -E '^fallback-body:' | grep -o 'subnormal-cosines-as-zero=[a-z]*')" \
    "subnormal-cosines-as-zero=no" "ir --plan: exact double body keeps subnormal cosines"
run "$FACET" ir test.mat --simd --plan --math fast
expect_eq "$(printf '%s\n' "$out" | grep -E '^(variant|batch-bodies):')" \
    "variant: fast"$'\n'"batch-bodies: float-first" "ir --plan --math fast"
expect_eq "$(printf '%s\n' "$out" | grep -E '^fallback-body:' | grep -o 'subnormal-cosines-as-zero=[a-z]*')" \
    "subnormal-cosines-as-zero=yes" "ir --plan --math fast: the plain fast body reads subnormal cosines as 0"
run "$FACET" ir test.mat --simd --plan --assume unit
expect_eq "$(printf '%s\n' "$out" | grep -E '^trust-inputs:')" "trust-inputs: yes" "ir --plan --assume unit"
run "$FACET" ir test.mat --plan --assume nothing
expect_rc 2 "ir --assume with an unknown promise"
expect_first_line "$err" "facet: assume 'nothing' is not unit or none" "ir --assume nothing: message"
run "$FACET" ir test.mat --plan --stages
expect_rc 2 "ir --plan with --stages"
expect_first_line "$err" "facet: ir: --stages and --plan exclude each other" "ir --plan --stages: message"
run "$FACET" render test.mat -o r.png --set nosuch=1 --size 16
expect_rc 2 "render --set of an unknown input: the same exit code as eval"
run "$FACET" eval test.mat --math fast --in dirs.csv
expect_rc 2 "--math with the interp backend"
expect_first_line "$err" "facet: eval: --math applies to the scalar and simd backends; the interp backend computes in double (add --backend scalar or simd)" \
    "--math with the interp backend: message"

# ---- usage errors ------------------------------------------------------------------
run "$FACET"
expect_rc 2 "no arguments"
run "$FACET" frobnicate
expect_rc 2 "unknown command"
expect_first_line "$err" "facet: unknown command 'frobnicate'" "unknown command: message"
run "$FACET" eval test.mat
expect_rc 2 "eval without --in"
expect_first_line "$err" "facet: eval: --in IN.csv is required" "eval without --in: message"
run "$FACET" eval --in dirs.csv
expect_rc 2 "eval without a material file"
run "$FACET" eval test.mat --in
expect_rc 2 "--in without a value"
run "$FACET" eval test.mat --in dirs.csv --frobnicate
expect_rc 2 "unknown eval option"
run "$FACET" eval test.mat other.mat --in dirs.csv
expect_rc 2 "two material files"
run "$FACET" eval test.mat --backend bogus --in dirs.csv
expect_rc 2 "unknown backend"
run "$FACET" check --frobnicate
expect_rc 2 "unknown check option"
run "$FACET" --help
expect_rc 0 "--help"
expect_first_line "$out" "usage: facet <command> [options]" "--help prints usage on stdout"

# ---- outputs over inputs ---------------------------------------------------------
cp test.mat keep.mat
run "$FACET" eval keep.mat --in dirs.csv --out ./keep.mat
expect_rc 2 "eval --out over the material file"
expect_first_line "$err" "facet: error: ./keep.mat is the same file as the material file keep.mat; facet eval does not write an output over the material file" \
    "eval over the material: message"
run "$FACET" eval test.mat --in dirs.csv --out dirs.csv
expect_rc 2 "eval --out over the input CSV"
run "$FACET" lut keep.mat -o keep.mat
expect_rc 2 "lut -o over the material file"
cmp -s test.mat keep.mat || fail "a refused output changed the material file"

# ---- the table cache -------------------------------------------------------------
# The interp backend reads and writes the tables the kernels use: the first
# run leaves them in the cache, a corrupt one is rebuilt with a warning
# saying why, and a cache root that is a regular file is named as such.
cat >kc.mat <<'MAT'
material kc { ndf = gtr(0.4, 2); masking = smith_separable; fresnel = schlick(0.04); energy = kulla_conty; }
MAT
mkdir -m 700 cache
FACET_CACHE_DIR=$PWD/cache run "$FACET" eval kc.mat --in dirs.csv --out kc1.csv
expect_rc 0 "interp with tables"
checks=$((checks + 1))
[ -f cache/tables/kc_gtr_g2_smith_separable.exr ] && [ -f cache/tables/lambda_gtr_g2.bin ] ||
    fail "the interp backend left no tables in the cache: $(ls -R cache)"
printf 'garbage' | dd of=cache/tables/lambda_gtr_g2.bin bs=1 seek=100 conv=notrunc 2>/dev/null
FACET_CACHE_DIR=$PWD/cache run "$FACET" eval kc.mat --in dirs.csv --out kc2.csv
expect_rc 0 "interp with a corrupt table"
expect_first_line "$err" "facet: warning: table lambda_gtr_g2 cannot be used (corrupt: $PWD/cache/tables/lambda_gtr_g2.bin: bad header line 'stegarbage5'); rebuilding it and rewriting the file" \
    "a rebuilt table is reported"
cmp -s kc1.csv kc2.csv || fail "the rebuilt table gave other values"
FACET_CACHE_DIR=$PWD/cache run "$FACET" eval kc.mat --in dirs.csv --out kc3.csv
expect_eq "$err" "" "the rewritten table is used without a word"
touch not-a-dir
FACET_CACHE_DIR=$PWD/not-a-dir run "$FACET" eval kc.mat --in dirs.csv --out kc4.csv
expect_rc 0 "a cache root that is a file"
expect_eq "$err" "facet: warning: not using the cache in $PWD/not-a-dir: $PWD/not-a-dir is a regular file, not a directory; running without a disk cache" \
    "a cache root that is a file: one warning naming it"
# A relative XDG_CACHE_HOME is ignored (the XDG base directory
# specification): the cache goes to $HOME/.cache/facet, not ./rel.
mkdir home
(unset FACET_CACHE_DIR; HOME=$PWD/home XDG_CACHE_HOME=rel run "$FACET" eval kc.mat --in dirs.csv --out kc5.csv)
checks=$((checks + 1))
[ ! -e rel ] && [ -d home/.cache/facet/tables ] || fail "a relative XDG_CACHE_HOME was used: $(ls)"

echo "cli_test: $checks checks, $failures failed"
[ "$failures" -eq 0 ]
