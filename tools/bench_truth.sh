#!/usr/bin/env bash
# Every method against the truth: a converged, unbiased image of our
# reference path tracer (rendered once per scene and resolution, in two
# independent halves whose difference gives its own noise; cached in the
# output folder, never in the repository). Budgets are whole runs in
# seconds (photons, cache and pre-passes included); the tables report RMSE,
# relMSE, the low-frequency error (8x8 block means over the truth's mean) and
# the convergence slope per method, where a ratio near 1 between the last
# budget and a quarter of it is a plateau.
# Usage: tools/bench_truth.sh [OUT] [SCENE...]
# Environment: RES (default 160x120), BUDGETS (seconds, default 4,8,16,32,64),
# METHODS (default uniform,transmittance,guided,reference), TRUTH_SPP_<scene>.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/bench_out/truth}"
shift || true
RES="${RES:-160x120}"
BUDGETS="${BUDGETS:-4,8,16,32,64}"
METHODS="${METHODS:-uniform,transmittance,guided,reference}"
V="$ROOT/build/bin/vdbmarch"
S="$ROOT/vdb_samples/scenes"
SCENES=("$@")
[ ${#SCENES[@]} -eq 0 ] && SCENES=(cloud_sun exp1_sphere fig3b_spots plume_emission)
mkdir -p "$OUT"
for name in "${SCENES[@]}"; do
  var="TRUTH_SPP_${name}"
  spp="${!var:-16384}"
  echo "== $name (truth: reference at $spp spp)" >&2
  "$V" bench "$S/$name.json" -o "$OUT/$name" --methods "$METHODS" --budgets "$BUDGETS" --seconds \
      --res "$RES" --reference-spp "$spp" --strip "$OUT/$name/strip.png"
done
