#!/usr/bin/env bash
# `facet bench --quick --json` on one material, end to end: exit 0 within
# seconds, JSON on stdout that parses with every field, and bench.md,
# bench.json and a 1600x1000 bench.png in --out DIR. With KC_MATERIAL.mat
# (energy = kulla_conty), also its Kulla-Conty table fields (energy_table:
# cold build and cached load) in the JSON and its line in bench.md.
# usage: bench_cli_test.sh FACET MATERIAL.mat OUTDIR [KC_MATERIAL.mat]
set -euo pipefail
facet=$1 material=$2 out=$3 kc_material=${4:-}
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
              "energy_table", "regular_lanes", "hard_lanes", "summary", "rows"):
        assert k in m, (path, k)
    assert m["energy_table"] is None, m["energy_table"]  # energy = none
    row_keys = ("backend", "mode", "options", "variant", "measured_error", "width", "lanes", "runs", "ns_per_eval",
                "ns_per_eval_min", "evals_per_second", "compile_cold_ms", "compile_tier_up_ms",
                "compile_cold_optimized_ms", "compile_memory_hit_ms",
                "compile_disk_hit_ms", "jit_over_aot", "jit_over_bare", "error_regular", "error_hard")
    err_keys = ("values", "skipped", "nonfinite", "negative", "invalid_lanes", "reference_invalid_lanes", "max_rel",
                "p999_rel", "max_ulp", "worst")
    rows = {(r["backend"], r["mode"]) for r in m["rows"]}
    assert len(m["rows"]) == 14, len(m["rows"])
    for r in m["rows"]:
        for k in row_keys:
            assert k in r, (path, k)
        # The bare row's host promises valid input: no hard-case error.
        for e in ("error_regular",) if r["mode"] == "bare" else ("error_regular", "error_hard"):
            for k in err_keys:
                assert k in r[e], (path, e, k)
    for b in ("interp", "scalar", "simd"):
        for mode in ("exact", "fast", "tol 1e-3", "tol 1e-5"):
            assert (b, mode) in rows, (b, mode)
    assert ("aot", "hand-written") in rows and ("aot", "bare") in rows
    sizes = {r["evaluator"]: r["ns_per_eval"] for r in m["batch_sizes"]}
    assert set(sizes) == {"simd exact", "simd fast", "simd exact, assume=unit", "simd fast, assume=unit",
                          "aot hand-written", "aot bare", "scalar exact, one call per lane"}, sizes
    for ns in sizes.values():
        assert set(ns) == {"1", "4", "16", "64", "256", "65536"}, ns
        assert ns["1"] > 0, ns
with open(out + "/report/bench.png", "rb") as f:
    head = f.read(24)
assert head[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", head[16:24])
assert (width, height) == (1600, 1000), (width, height)
md = open(out + "/report/bench.md").read()
assert "## ggx_schlick" in md and "JIT/AOT" in md and "JIT/bare" in md and "Batch sizes" in md
print("ok: JSON parses with every field; bench.md; bench.png 1600x1000")
PY

[[ -z "$kc_material" ]] && exit 0
"$facet" bench --quick --json --out "$out/kc" "$kc_material" >"$out/kc.json"
python3 - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
for path in (out + "/kc.json", out + "/kc/bench.json"):
    with open(path) as f:
        m = json.load(f)["materials"][0]
    e = m["energy_table"]
    assert isinstance(e, dict), (path, e)
    for k, t in (("pair", str), ("ndf", str), ("masking", str), ("key", str), ("build_ms", (int, float)),
                 ("build_threads", int), ("cached_load_ms", (int, float)), ("cached_load_runs", int),
                 ("grid", list), ("cache_file", str), ("note", str)):
        assert isinstance(e.get(k), t), (path, k, e.get(k))
    assert e["pair"] == e["ndf"] + " x " + e["masking"], e
    assert e["build_ms"] > 0 and e["cached_load_ms"] > 0 and e["build_threads"] >= 1, e
    assert e["grid"] == [64, 64], e["grid"]
    assert e["note"] == "" and os.path.exists(e["cache_file"]), e
    assert m["kulla_conty_ms"] == e["build_ms"] and m["kulla_conty_pair"] == e["key"], m
md = open(out + "/kc/bench.md").read()
line = "Kulla-Conty tables: %s (%s), built in " % (e["pair"], e["key"])
assert line in md and " / loaded from cache in " in md, md[:2000]
assert md.index(line) < md.index("| backend |")
print("ok: %s: energy_table %s, built in %.0f ms, loaded from cache in %.2f ms"
      % (m["material"], e["pair"], e["build_ms"], e["cached_load_ms"]))
PY
