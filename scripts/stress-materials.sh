#!/usr/bin/env bash
# Compile time and peak memory of the front end's stress materials on every
# backend: 1k and 10k unused inputs, a 100k let chain, a 20k rgb mix chain
# (and, for scale, the largest chain the compute budget accepts). Each row:
# the command's exit code, its wall time and its peak resident memory, for
# `facet check`, `facet eval` (one row; the process waits for the optimized
# code, FACET_CACHE_DIR being set) and `facet sample` (the compiled sampler).
#
#   scripts/stress-materials.sh [build/bin/facet]
set -euo pipefail
facet=$(realpath "${1:-build/bin/facet}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
export FACET_CACHE_DIR="$work/cache"

python3 - <<'PY'
def header(name): return f"material {name} {{\n"
def models(alpha="0.3", diffuse=None):
    s = f"    ndf = ggx({alpha});\n    masking = smith_height_correlated;\n    fresnel = schlick(0.04);\n"
    if diffuse: s += f"    diffuse = lambert({diffuse});\n"
    return s + "}\n"
def unused(n):
    return header("unused") + "".join(f"    input u{i} = 0.5 in 0 .. 1;\n" for i in range(n)) + models()
def chain(n):
    s = header("chain") + "    input r = 0.5 in 0 .. 1;\n    let a0 = r;\n"
    s += "".join(f"    let a{i} = a{i - 1} + 0.000001;\n" for i in range(1, n))
    return s + models(f"clamp(a{n - 1}, 0.01, 1)")
def mix(n):
    s = header("mixchain") + "    input t = 0.5 in 0 .. 1;\n    input c = rgb(0.2, 0.3, 0.4);\n    let m0 = c;\n"
    s += "".join(f"    let m{i} = mix(m{i - 1}, rgb(0.5, 0.5, 0.5), t);\n" for i in range(1, n))
    return s + models(diffuse=f"m{n - 1}")
for name, text in [("unused1k", unused(1000)), ("unused10k", unused(10000)), ("chain100k", chain(100000)),
                   ("mix20k", mix(20000)), ("chain3900", chain(3900)), ("mix435", mix(435))]:
    open(name + ".mat", "w").write(text)
PY
printf 'wi_x,wi_y,wi_z,wo_x,wo_y,wo_z\n0,0,1,0.6,0,0.8\n' >one.csv

# measure LABEL CMD...: exit code, seconds, peak MiB of one run.
measure() {
    local label=$1
    shift
    python3 -c 'import resource, subprocess, sys, time
start = time.monotonic()
rc = subprocess.run(sys.argv[2:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
secs = time.monotonic() - start
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
print(f"| {sys.argv[1]} | {rc} | {secs:.2f} | {peak:.0f} |")' "$label" "$@"
}

echo "| material, command | exit | seconds | peak MiB |"
echo "|---|--:|--:|--:|"
for m in unused1k unused10k chain100k mix20k chain3900 mix435; do
    measure "$m check" "$facet" check "$m.mat"
    for backend in interp scalar simd; do
        measure "$m eval --backend $backend" "$facet" eval "$m.mat" --backend "$backend" --in one.csv
        measure "$m sample --backend $backend" "$facet" sample "$m.mat" --backend "$backend" --wo 0.6,0,0.8 -n 1000
    done
done
