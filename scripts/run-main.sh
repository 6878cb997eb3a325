#!/usr/bin/env bash
# The README's main command: install what is missing, build, and run Facet on
# every shipped material: check them, then `facet bench` (speed against error
# for every backend x math mode, with the AOT baseline where one exists) on
# the shipped and reference materials, one line of progress per file. Tables:
# terminal, build/bench/bench.md, bench.json, bench.png. Then the previews:
# a lit sphere per material and the plots in build/gallery
# (scripts/gallery.sh, the same command that made docs/gallery).
#
#   scripts/run-main.sh          under 3 minutes after the build: 7 timed runs
#                                of 16384 lanes and 1 timed compile of each kind
#                                a row
#   scripts/run-main.sh --full   the bench's own defaults (15 runs of 65536
#                                lanes, 7 compiles): steadier figures, several
#                                times longer
set -euo pipefail
cd "$(dirname "$0")/.."
bench_settings=(--runs 7 --lanes 16384 --compile-runs 1)
case "${1:-}" in
    --full) bench_settings=() ;;
    "") ;;
    *) echo "usage: scripts/run-main.sh [--full]" >&2; exit 2 ;;
esac
start=$SECONDS
scripts/install-deps.sh
scripts/build.sh
echo "build ready after $((SECONDS - start)) s"
facet=build/bin/facet
run_start=$SECONDS
$facet check materials/*.mat
echo "all $(ls materials/*.mat | wc -l) materials check"
$facet bench materials/*.mat bench/models/*.mat --out build/bench "${bench_settings[@]}"
echo "bench done after $((SECONDS - run_start)) s; the gallery next"
scripts/gallery.sh build/gallery
echo "main job: $((SECONDS - run_start)) s after the build"
