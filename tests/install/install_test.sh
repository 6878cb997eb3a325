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
# The Python package, when this build has one: installed below the prefix
# (FACET_PYTHON_INSTALL_DIR) and importable from there alone.
py_dir=$(sed -n 's/^FACET_PYTHON_INSTALL_DIR:[A-Z]*=//p' "$build_dir/CMakeCache.txt")
python=$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build_dir/CMakeCache.txt")
if [ -n "$py_dir" ] && [ -n "$python" ]; then
  case $py_dir in /*) site=$py_dir ;; *) site=$work/prefix/$py_dir ;; esac
  [ -f "$site/facet/__init__.py" ] || { echo "no facet package in $site"; exit 1; }
  got=$(cd "$work" && PYTHONPATH="$site" PYTHONDONTWRITEBYTECODE=1 "$python" -c "
import facet, sys
assert facet.__file__.startswith('$site'), facet.__file__
print('%.8f' % facet.compile('$work/m.mat').eval([0, 0, 1], [0, 0, 1])[0])")
  echo "python: $got"
  awk -v g="$got" 'BEGIN { d = g - 1.27323954; exit !(d < 2e-6 && d > -2e-6) }' ||
    { echo "the installed package printed $got, expected 1.27323954"; exit 1; }
fi
