#!/usr/bin/env bash
# verify_transmission.sh: `facet verify` on the shipped materials that
# scatter below the surface (examples/materials: rough glass, frosted glass
# with energy compensation, a thin leaf): exit 0, the furnace table from both
# sides, the compensated furnace within SPEC 11's 1%, generalized
# reciprocity, and SPEC 11's hard pairs (critical angle, wi = -wo) among the
# hard cases, compared with the compiled kernels (the compensated frosted
# glass's too). A material that breaks a bound makes verify exit 1.
#   usage: verify_transmission.sh PATH/TO/facet SOURCE_DIR
set -u
FACET=${1:?usage: verify_transmission.sh PATH/TO/facet SOURCE_DIR}
SRC=${2:?usage: verify_transmission.sh PATH/TO/facet SOURCE_DIR}
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
out=$("$FACET" verify "$SRC"/examples/materials/{rough_glass,frosted_glass,leaf}.mat --verbose 2>&1)
rc=$?
echo "$out"
[ "$rc" -eq 0 ] || fail "facet verify exited $rc"
for needle in "verify: 3 of 3 materials passed" "white furnace, R + T over the sphere" \
    "1.00    1.52 inside" "compensated furnace" "generalized reciprocity" "scalar exact" "scalar fast"; do
    case "$out" in *"$needle"*) ;; *) fail "'$needle' not in the output" ;; esac
done
case "$out" in *"not compiled"*) fail "a material's kernels were not compiled" ;; esac
[ "$(grep -c 'compensated furnace .*  ok ' <<<"$out")" -eq 3 ] || fail "not three compensated furnace rows marked ok"
[ "$(grep -c 'generalized reciprocity .*  ok ' <<<"$out")" -eq 3 ] || fail "not three reciprocity rows marked ok"
echo "$failures failures"
[ "$failures" -eq 0 ]
