#!/usr/bin/env bash
# Installs the built Facet into a temporary prefix, builds a consumer
# project against it with find_package(Facet), and runs both consumers on a
# material whose normal-incidence value is known: GGX alpha = 0.25, F = 1,
# f = 1/(4 pi alpha^2) = 1.27323954. The third consumer gets the material
# compiled ahead of time through facet_add_material() and must not link Facet;
# it also checks the object's sampler (pdf at normal incidence, one sample).
set -euo pipefail
build_dir=$1 source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
echo 'material m { ndf = ggx(0.25); }' > "$work/m.mat"
cmake -S "$source_dir/tests/install/consumer" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DFACET_TEST_MATERIAL="$work/m.mat" >/dev/null
cmake --build "$work/build" >/dev/null
if readelf -d "$work/build/consumer_aot" | grep -E 'NEEDED.*(facet|LLVM)'; then
  echo "consumer_aot links Facet or LLVM"; exit 1
fi
for exe in consumer_c consumer_cxx consumer_aot; do
  got=$("$work/build/$exe" "$work/m.mat")
  echo "$exe: $got"
  awk -v g="$got" 'BEGIN { d = g - 1.27323954; exit !(d < 2e-6 && d > -2e-6) }' ||
    { echo "$exe printed $got, expected 1.27323954"; exit 1; }
done
