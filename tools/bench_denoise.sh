#!/usr/bin/env bash
# The denoiser and the noise estimate against the truth, at equal time
# (docs/denoise.md; BENCHMARKS.md, "Denoising and the noise target").
# For each scene: a truth (TRUTH_METHOD, by default the path tracer, at
# TRUTH_FACTOR x the largest budget, another seed, sampled evenly), whose own
# noise (its two halves' estimate) is subtracted from every MSE; then at each
# budget one render of the default method with --denoise and --time (the
# denoiser's predicted time kept back from the budget, adaptive sampling on
# unless EXTRA turns it off), whose
# RGBA is the denoised image and whose `noisy` layer the raw one: the same
# samples, so the two differ by the denoiser alone. Each against the truth:
# RMSE net of the truth's noise, low-frequency error, and the render's own
# noise estimate beside its measured error.
# Usage: tools/bench_denoise.sh OUT SCENE...   (env: RES 160x120, BUDGETS "16",
# THREADS 2, TRUTH_FACTOR 8, TRUTH_METHOD reference, BIN build/bin/vdbmarch,
# EXTRA extra render options). TRUTH_METHOD must be unbiased: `guided` (its
# default L_i, "path") gives single-scattering scenes such as the plume a
# truth with about a third of the path tracer's noise (RMSE) for the same time.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$1"; shift
BIN="${BIN:-$ROOT/build/bin/vdbmarch}"; RES="${RES:-160x120}"; BUDGETS="${BUDGETS:-16}"
THREADS="${THREADS:-2}"; TRUTH_FACTOR="${TRUTH_FACTOR:-8}"; EXTRA="${EXTRA:-}"
TRUTH_METHOD="${TRUTH_METHOD:-reference}"
mkdir -p "$OUT"
field() { python3 -c "import json,sys; d=json.load(open('$1')); print(eval('d'+sys.argv[1]))" "$2"; }
metric() { "$BIN" compare "$1" "$2" ${4:+--layer "$4"} | awk -v k="$3" '$1 == k {print $2}'; }
echo "| scene | res | budget s | mean spp | raw RMSE / truth-noise-net | denoised RMSE net | MSE ratio | raw LF | denoised LF | raw noise estimated / measured (rel.) | truth rel. noise | denoise s |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for scene in "$@"; do
    name=$(basename "$scene" .json)
    max=0; for b in $BUDGETS; do max=$(python3 -c "print(max($max, $b))"); done
    truth="$OUT/$name.$RES.$TRUTH_METHOD.truth.exr"
    if [ ! -f "$truth" ]; then
        "$BIN" render "$scene" -o "$truth" --res "$RES" --threads "$THREADS" --method "$TRUTH_METHOD" \
            --time "$(python3 -c "print($max * $TRUTH_FACTOR)")" --seed 777 --no-denoise -q --stats "$truth.json" $EXTRA \
            --set experiments.adaptive=false
    fi
    tn=$(field "$truth.json" "['noise_estimate']['rmse']")
    tm=$(field "$truth.json" "['noise_estimate']['mean']")
    for b in $BUDGETS; do
        run="$OUT/$name.$RES.$b.exr"
        "$BIN" render "$scene" -o "$run" --res "$RES" --threads "$THREADS" --time "$b" --seed 11 --denoise -q \
            --stats "$run.json" $EXTRA
        dsec=$(field "$run.json" "['seconds']['denoise']")
        rr=$(metric "$run" "$truth" rmse noisy); rd=$(metric "$run" "$truth" rmse)
        lr=$(metric "$run" "$truth" low_frequency_error noisy); ld=$(metric "$run" "$truth" low_frequency_error)
        spp=$(field "$run.json" "['mean_spp']"); est=$(field "$run.json" "['noise_estimate']['relative']")
        python3 - "$name" "$RES" "$b" "$spp" "$rr" "$rd" "$tn" "$tm" "$lr" "$ld" "$est" "$dsec" <<'PY'
import sys, math
name, res, b, spp, rr, rd, tn, tm, lr, ld, est, dsec = sys.argv[1:]
rr, rd, tn, tm, lr, ld, est = map(float, (rr, rd, tn, tm, lr, ld, est))
net = lambda r: math.sqrt(max(0.0, r * r - tn * tn))
nr, nd = net(rr), net(rd)
print(f"| {name} | {res} | {b} | {float(spp):.0f} | {rr:.4g} / {nr:.4g} | {nd:.4g} | {nd*nd/(nr*nr):.3f} | {lr:.4f} | {ld:.4f} | "
      f"{est:.4f} / {nr/tm:.4f} | {tn/tm:.4f} | {dsec} |")
PY
    done
done
