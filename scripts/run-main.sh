#!/usr/bin/env bash
# The README's main command: install what is missing, build, and run Facet on
# every shipped material: check them, then `facet bench` (speed against error
# for every backend x math mode, with the AOT baseline where one exists).
# Tables: terminal, build/bench/bench.md, bench.json, bench.png. Then the
# previews: a lit sphere per material and the plots in build/gallery
# (scripts/gallery.sh, the same command that made docs/gallery).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
facet=build/bin/facet
$facet check materials/*.mat
echo "all $(ls materials/*.mat | wc -l) materials check"
$facet bench materials/*.mat bench/models/*.mat --out build/bench
scripts/gallery.sh build/gallery
