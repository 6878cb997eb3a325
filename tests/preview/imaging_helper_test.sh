#!/usr/bin/env bash
# `facet` without OpenImageIO (apps/cli/ImagingHelper.h): neither `facet` nor
# libfacet.so loads it (their DT_NEEDED entries, read with readelf), and
# `facet render` hands over to facet-imaging beside facet only when that
# helper is trusted: missing, group-writable, in a directory others can
# write, or a symlink, it is refused with exit 1 and a message naming the
# helper's path and the reason; a trusted copy renders.
# usage: imaging_helper_test.sh FACET FACET_IMAGING LIBFACET SOURCE_DIR OUTDIR
set -uo pipefail
facet=$1 helper=$2 libfacet=$3 src=$4 out=$5
rm -rf "$out"
mkdir -p "$out"
fail=0
needed() { readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'; }
for f in "$facet" "$libfacet"; do
  if needed "$f" | grep -q -i openimageio; then echo "FAIL: $f needs OpenImageIO:"; needed "$f"; fail=1; fi
done
# The positive control: the picture binary does need it.
needed "$helper" | grep -q -i openimageio || { echo "FAIL: $helper does not need OpenImageIO"; fail=1; }

# A copy of facet in a directory of its own, as an installation would have it.
solo=$out/solo
mkdir -p "$solo"
chmod 755 "$solo"
cp "$facet" "$solo/facet"
mat=$src/materials/gold.mat
try() {  # try DESCRIPTION EXPECTED_EXIT PATTERN: `facet render` from the copy
  "$solo/facet" render "$mat" -o "$out/gold.png" --size 64 --samples 2 >"$out/stdout" 2>"$out/stderr"
  local got=$?
  if [[ $got -ne $2 ]]; then echo "FAIL: $1: exit $got, expected $2"; cat "$out/stdout" "$out/stderr"; fail=1; fi
  if ! grep -q -- "$3" "$out/stderr" "$out/stdout"; then echo "FAIL: $1: '$3' not printed:"; cat "$out/stderr"; fail=1; fi
}
try "no helper" 1 "$solo/facet-imaging: No such file or directory"
ln -s "$helper" "$solo/facet-imaging"
try "helper is a symlink" 1 "$solo/facet-imaging: Too many levels of symbolic links"
rm "$solo/facet-imaging"
cp "$helper" "$solo/facet-imaging"
chmod 775 "$solo/facet-imaging"
try "group-writable helper" 1 "$solo/facet-imaging is writable by group or others"
chmod 755 "$solo/facet-imaging"
chmod 777 "$solo"
try "world-writable directory" 1 "$solo is writable by group or others"
chmod 755 "$solo"
try "trusted helper" 0 "rendered 64x64"
[[ -s "$out/gold.png" ]] || { echo "FAIL: the trusted helper wrote no $out/gold.png"; fail=1; }
# bench goes the same way (its usage error comes from facet-imaging).
"$solo/facet" bench >"$out/stdout" 2>"$out/stderr"
got=$?
[[ $got -eq 2 ]] || { echo "FAIL: bench without files: exit $got, expected 2"; fail=1; }
grep -q "no material files given" "$out/stderr" || { echo "FAIL: bench usage error not printed"; cat "$out/stderr"; fail=1; }
rm -rf "$solo"
[[ $fail -eq 0 ]] && echo "imaging helper: all checks passed"
exit $fail
