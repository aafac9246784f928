#!/usr/bin/env bash
# Adaptive sampling (render --noise) against uniform sampling at equal time
# (docs/noise.md; BENCHMARKS.md). For each SCENE:TARGET, renders to the
# noise target with seeds 11 and 23, then uniformly (--time) for the mean
# time those took, also with seeds 11 and 23; both estimators are unbiased up
# to the stopping rule, so each side's MSE is its squared pair RMSE / 2.
# Usage: tools/bench_noise_target.sh OUT SCENE.json:TARGET...
# (env: RES 160x120, THREADS 2, BIN build/bin/vdbmarch)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$1"; shift
BIN="${BIN:-$ROOT/build/bin/vdbmarch}"; RES="${RES:-160x120}"; THREADS="${THREADS:-2}"
mkdir -p "$OUT"
field() { python3 -c "import json,sys; d=json.load(open('$1')); print(eval('d'+sys.argv[1]))" "$2"; }
rmse() { "$BIN" compare "$1" "$2" | awk '$1 == "rmse" {print $2}'; }
echo "| scene | target | adaptive s | adaptive mean / max spp | adaptive estimated | adaptive measured | uniform spp | uniform measured | MSE adaptive / uniform |"
echo "|---|---|---|---|---|---|---|---|---|"
for item in "$@"; do
    scene="${item%:*}"; target="${item##*:}"; name=$(basename "$scene" .json)
    t=0
    for s in 11 23; do
        "$BIN" render "$scene" -o "$OUT/$name.a$s.exr" --res "$RES" --threads "$THREADS" --noise "$target" --seed $s \
            --no-denoise -q --stats "$OUT/$name.a$s.json"
        t=$(python3 -c "print($t + $(field "$OUT/$name.a$s.json" "['seconds']['total']") / 2)")
    done
    for s in 11 23; do
        "$BIN" render "$scene" -o "$OUT/$name.u$s.exr" --res "$RES" --threads "$THREADS" --time "$t" --seed $s \
            --no-denoise -q --stats "$OUT/$name.u$s.json" --set experiments.adaptive=false
    done
    ra=$(rmse "$OUT/$name.a11.exr" "$OUT/$name.a23.exr"); ru=$(rmse "$OUT/$name.u11.exr" "$OUT/$name.u23.exr")
    python3 - "$name" "$target" "$t" "$ra" "$ru" \
        "$(field "$OUT/$name.a11.json" "['mean_spp']")" "$(field "$OUT/$name.a11.json" "['spp']")" \
        "$(field "$OUT/$name.a11.json" "['noise_estimate']['relative']")" \
        "$(field "$OUT/$name.a11.json" "['noise_estimate']['mean']")" "$(field "$OUT/$name.u11.json" "['spp']")" <<'PY'
import sys, math
name, target, t, ra, ru, mspp, spp, est, mean, uspp = sys.argv[1:]
ra, ru, mean = float(ra) / math.sqrt(2), float(ru) / math.sqrt(2), float(mean)
print(f"| {name} | {target} | {float(t):.1f} | {float(mspp):.0f} / {spp} | {float(est):.3f} | {ra/mean:.3f} | {uspp} | {ru/mean:.3f} | {ra*ra/(ru*ru):.2f} |")
PY
done
