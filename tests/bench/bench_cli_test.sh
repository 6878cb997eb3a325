#!/usr/bin/env bash
# `facet bench --quick --json` on one material, end to end: exit 0 within
# seconds, JSON on stdout that parses with every field, and bench.md,
# bench.json and a 1600x1000 bench.png in --out DIR.
# usage: bench_cli_test.sh FACET MATERIAL.mat OUTDIR
set -euo pipefail
facet=$1 material=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
start=$(date +%s%N)
"$facet" bench --quick --json --out "$out/report" "$material" >"$out/stdout.json"
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
echo "facet bench --quick took ${elapsed_ms} ms"
# "A few seconds" on an idle machine; the bound leaves room for a loaded one.
if (( elapsed_ms > 60000 )); then echo "FAIL: bench --quick took ${elapsed_ms} ms"; exit 1; fi

python3 - "$out" <<'PY'
import json, struct, sys
out = sys.argv[1]
for path in (out + "/stdout.json", out + "/report/bench.json"):
    with open(path) as f:
        doc = json.load(f)  # must parse (strict: NaN/Infinity are not JSON)
    for k in ("facet_bench_format", "host", "settings", "materials"):
        assert k in doc, (path, k)
    assert len(doc["materials"]) == 1
    m = doc["materials"][0]
    for k in ("file", "material", "aot", "aot_note", "parse_check_ms", "kulla_conty_ms", "kulla_conty_pair",
              "regular_lanes", "hard_lanes", "summary", "rows"):
        assert k in m, (path, k)
    row_keys = ("backend", "mode", "options", "variant", "measured_error", "width", "lanes", "runs", "ns_per_eval",
                "ns_per_eval_min", "evals_per_second", "compile_cold_ms", "compile_memory_hit_ms",
                "compile_disk_hit_ms", "jit_over_aot", "error_regular", "error_hard")
    err_keys = ("values", "skipped", "nonfinite", "negative", "invalid_lanes", "reference_invalid_lanes", "max_rel",
                "p999_rel", "max_ulp", "worst")
    rows = {(r["backend"], r["mode"]) for r in m["rows"]}
    assert len(m["rows"]) == 13, len(m["rows"])
    for r in m["rows"]:
        for k in row_keys:
            assert k in r, (path, k)
        for e in ("error_regular", "error_hard"):
            for k in err_keys:
                assert k in r[e], (path, e, k)
    for b in ("interp", "scalar", "simd"):
        for mode in ("exact", "fast", "tol 1e-3", "tol 1e-5"):
            assert (b, mode) in rows, (b, mode)
    assert ("aot", "hand-written") in rows
with open(out + "/report/bench.png", "rb") as f:
    head = f.read(24)
assert head[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", head[16:24])
assert (width, height) == (1600, 1000), (width, height)
md = open(out + "/report/bench.md").read()
assert "## ggx_schlick" in md and "JIT/AOT" in md
print("ok: JSON parses with every field; bench.md; bench.png 1600x1000")
PY
