#!/usr/bin/env bash
# The README's main command: install what is missing, build, and run Facet on
# every shipped material (check, then evaluate a direction sample).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
facet=build/compiler/facet
$facet check materials/*.mat
echo "all $(ls materials/*.mat | wc -l) materials check"
sample=build/main-sample.csv
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n0,0,1,0,0,1\n0.6,0,0.8,-0.6,0,0.8\n0.8,0.0,0.6,-0.48,0.64,0.6\n0.9949874,0,0.1,-0.9949874,0,0.1\n' > "$sample"
for m in materials/*.mat; do
  echo "== $m"
  $facet eval "$m" --in "$sample"
done
