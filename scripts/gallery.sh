#!/usr/bin/env bash
# The README gallery: one lit sphere per shipped material (256x256, default
# light and sky, 64 sky samples, SIMD exact kernel), the NDF comparison at
# matched roughness, the lobe plots of two materials and the sample
# histograms of two (beside their integrated pdfs), a rough gold lobe beside
# its random-walk reference (a material written under build/), frosted glass
# lit from behind and rough glass's lobe over the whole circle, all written by
# `facet render` into OUTDIR (default docs/gallery, the committed images).
# Expects a built tree (scripts/build.sh); run from anywhere.
# usage: scripts/gallery.sh [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/gallery}
facet=build/bin/facet
mkdir -p "$out"
# The spheres two at a time (each render is one thread; the images do not
# depend on what else runs).
ls materials/*.mat | xargs -P 2 -I{} sh -c \
  'set -e; f="$1"; n=$(basename "$f" .mat); "$2" render "$f" -o "$3/$n.png" --size 256 --samples 64 | grep -E "^rendered"' \
  sh {} "$facet" "$out"
$facet render --plot ndf --compare gtr:gamma=1,beckmann,blinn_phong,ggx,gtr:gamma=1.5,student_t:gamma=3,gaussian,epd:p=0.5,abc:c=1.5,sgd:p=1 \
  --alpha 0.3 -o "$out/ndf_compare.png"
$facet render materials/plastic.mat --plot lobe -o "$out/lobe_plastic.png"
$facet render materials/gold.mat --plot lobe -o "$out/lobe_gold.png"
$facet render materials/plastic.mat --plot pdf --wo 0.6,0,0.8 -o "$out/pdf_plastic.png"
$facet render materials/brushed_metal.mat --plot pdf --wo 0.7071068,0,0.7071068 -o "$out/pdf_brushed_metal.png"
# A refracting lobe (the reference: the compiled backends do not take it
# yet): frosted glass lit through from behind, rough glass's lobe over the
# whole circle.
$facet render examples/materials/frosted_glass.mat --backend interp -o "$out/frosted_glass.png" --size 256 \
  --samples 64 | grep -E "^rendered"
$facet render examples/materials/rough_glass.mat --plot lobe -o "$out/lobe_rough_glass.png"
mkdir -p build/gallery-materials
printf 'material rough_gold { ndf = ggx(0.8); masking = smith_height_correlated; fresnel = conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603)); energy = kulla_conty; }\n' \
  > build/gallery-materials/rough_gold.mat
$facet render build/gallery-materials/rough_gold.mat --plot walk --theta-i 60 -o "$out/walk_rough_gold.png"
echo "gallery written to $out"
