#!/usr/bin/env bash
# `facet render` end to end: a sphere PNG and EXR, the lobe, NDF and pdf plots,
# each file read back at its requested size (oiiotool --info), the timing
# line printed; and the errors: usage mistakes exit 2 with a message naming
# the option, a material file error exits 65 with file:line:col, an
# unwritable output exits 1.
# usage: render_cli_test.sh FACET SOURCE_DIR OUTDIR
set -uo pipefail
facet=$1 src=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
fail=0
check() {  # check DESCRIPTION EXPECTED_EXIT COMMAND...
  local what=$1 want=$2
  shift 2
  "$@" >"$out/stdout" 2>"$out/stderr"
  local got=$?
  if [[ $got -ne $want ]]; then
    echo "FAIL: $what: exit $got, expected $want"; cat "$out/stdout" "$out/stderr"; fail=1
  fi
}
expect_text() {  # expect_text DESCRIPTION FILE PATTERN
  if ! grep -q -- "$3" "$2"; then echo "FAIL: $1: '$3' not in $2:"; cat "$2"; fail=1; fi
}
size_of() { oiiotool --info "$1" | sed -E 's/^[^:]*: *([0-9]+) x +([0-9]+),.*/\1 x \2/'; }

check "sphere png" 0 "$facet" render "$src/materials/gold.mat" -o "$out/gold.png" --size 96 --samples 8
expect_text "sphere png" "$out/stdout" "rendered 96x96"
expect_text "sphere png timing" "$out/stdout" "kernel lanes in [0-9.]* s on [0-9]* threads"
[[ "$(size_of "$out/gold.png")" == "96 x 96" ]] || { echo "FAIL: gold.png is $(size_of "$out/gold.png")"; fail=1; }

check "sphere exr" 0 "$facet" render "$src/materials/brushed_metal.mat" -o "$out/brushed.exr" --size 64 \
  --samples 4 --light 60,30 --view 20,90 --sky constant --backend scalar --math fast
[[ "$(size_of "$out/brushed.exr")" == "64 x 64" ]] || { echo "FAIL: brushed.exr size"; fail=1; }
oiiotool --info -v "$out/brushed.exr" | grep -q "4 channel" || { echo "FAIL: brushed.exr is not RGBA"; fail=1; }

check "lobe plot" 0 "$facet" render "$src/materials/plastic.mat" --plot lobe -o "$out/lobe.png" --size 640 --theta-i 0,45
expect_text "lobe plot" "$out/stdout" "theta_i 45: peak"
[[ "$(size_of "$out/lobe.png")" == "640 x 400" ]] || { echo "FAIL: lobe.png is $(size_of "$out/lobe.png")"; fail=1; }

check "ndf plot" 0 "$facet" render "$src/materials/aluminium.mat" --plot ndf -o "$out/ndf.png" --alpha 0.1,0.5
[[ "$(size_of "$out/ndf.png")" == "960 x 600" ]] || { echo "FAIL: ndf.png is $(size_of "$out/ndf.png")"; fail=1; }
check "ndf compare" 0 "$facet" render --plot ndf --compare ggx,beckmann,blinn_phong --alpha 0.3 -o "$out/cmp.png"
expect_text "ndf compare" "$out/stdout" "3 curves"
check "ndf compare with shapes" 0 "$facet" render --plot ndf --compare gtr:gamma=1,student_t:gamma=3,student_t --alpha 0.2,0.4 -o "$out/cmp2.png"
expect_text "ndf compare with shapes" "$out/stdout" "6 curves"
# A shape value changes the curve: gamma = 3 and the typical gamma = 2 (GGX) differ.
cmp -s "$out/cmp.png" "$out/cmp2.png" && { echo "FAIL: the shape values did not change the plot"; fail=1; }

check "pdf plot" 0 "$facet" render "$src/materials/plastic.mat" --plot pdf --wo 0.6,0,0.8 -n 200000 -o "$out/pdf.png" --size 600
[[ "$(size_of "$out/pdf.png")" == "600 x 225" ]] || { echo "FAIL: pdf.png is $(size_of "$out/pdf.png")"; fail=1; }
expect_text "pdf plot" "$out/stdout" "200000 samples (0 with no direction), 4608 cells: pdf integral "
# The cells' pdf integral is 1 within the quadrature's tolerance (0.01/n per cell).
integral=$(sed -nE 's/.*pdf integral ([0-9.]+);.*/\1/p' "$out/stdout")
awk -v x="$integral" 'BEGIN { exit !(x != "" && x - 1 <= 1e-5 && 1 - x <= 1e-5) }' ||
  { echo "FAIL: pdf plot: integral '$integral' is not within 1e-5 of 1"; fail=1; }
expect_text "pdf plot chi-square" "$out/stdout" "degrees of freedom, p = "
check "pdf plot without wo" 2 "$facet" render "$src/materials/plastic.mat" --plot pdf -o "$out/x.png"
expect_text "pdf plot without wo" "$out/stderr" "--plot pdf needs --wo X,Y,Z"
check "pdf plot wo below" 2 "$facet" render "$src/materials/plastic.mat" --plot pdf --wo 0,0,-1 -o "$out/x.png"
expect_text "pdf plot wo below" "$out/stderr" "points into the surface"
check "wo with lobe" 2 "$facet" render "$src/materials/plastic.mat" --plot lobe --wo 0,0,1 -o "$out/x.png"
expect_text "wo with lobe" "$out/stderr" "--wo goes with --plot pdf"
check "no -o" 2 "$facet" render "$src/materials/gold.mat"
expect_text "no -o" "$out/stderr" "-o OUT is required"
check "bad light" 2 "$facet" render "$src/materials/gold.mat" -o "$out/x.png" --light 200,0
expect_text "bad light" "$out/stderr" "--light: theta 200 is outside"
check "bad size" 2 "$facet" render "$src/materials/gold.mat" -o "$out/x.png" --size abc
expect_text "bad size" "$out/stderr" "--size: 'abc' is not a finite number"
check "bad sky" 2 "$facet" render "$src/materials/gold.mat" -o "$out/x.png" --sky cloudy
expect_text "bad sky" "$out/stderr" "--sky expects gradient, constant or none"
check "bad compare" 2 "$facet" render --plot ndf --compare ggx,ward -o "$out/x.png"
expect_text "bad compare" "$out/stderr" "'ward' is not an NDF"
check "compare: unknown shape parameter" 2 "$facet" render --plot ndf --compare student_t:gama=3 -o "$out/x.png"
expect_text "compare: unknown shape parameter" "$out/stderr" "'student_t' has no shape parameter 'gama' (its shape parameters: gamma)"
check "compare: shape value outside" 2 "$facet" render --plot ndf --compare student_t:gamma=1 -o "$out/x.png"
expect_text "compare: shape value outside" "$out/stderr" "'gamma=1' is not NAME=VALUE with gamma in .1.5, 10000."
check "compare: no shape parameters" 2 "$facet" render --plot ndf --compare ggx:gamma=2 -o "$out/x.png"
expect_text "compare: no shape parameters" "$out/stderr" "'ggx' has no shape parameter 'gamma' (its shape parameters: none)"
check "unknown input (a usage error, as in eval and ir)" 2 "$facet" render "$src/materials/gold.mat" -o "$out/x.png" --set shininess=3
expect_text "unknown input" "$out/stderr" "--set: material 'gold' has no input 'shininess'"
printf 'material broken {\n    ndf = ggx(;\n}\n' >"$out/broken.mat"
check "material error" 65 "$facet" render "$out/broken.mat" -o "$out/x.png"
expect_text "material error" "$out/stderr" "broken.mat:2:"
check "unwritable" 1 "$facet" render "$src/materials/gold.mat" -o /nonexistent-dir/x.png --size 16 --samples 1
expect_text "unwritable" "$out/stderr" "cannot write"
exit $fail
