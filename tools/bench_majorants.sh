#!/usr/bin/env bash
# Local VDB-block majorants against one global majorant per grid, for the
# reference path tracer: same scene, seed and spp; median wall time of REPEATS
# alternating runs; and the two images compared (they estimate the same
# image, so their difference is noise).
# usage: tools/bench_majorants.sh [OUT_DIR] [REPEATS]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/bench_out/majorants}"
REPEATS="${2:-3}"
V="$ROOT/build/bin/vdbmarch"
mkdir -p "$OUT"
CASES=("sparse|$ROOT/vdb_samples/sparse.json|--spp 64 --res 320x240")
[ -f "$ROOT/../shared/assets/wdas_cloud_sixteenth.vdb" ] &&
  CASES+=("disney_cloud|$ROOT/../shared/assets/wdas_cloud_sixteenth.vdb|--spp 32 --res 320x240")
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
echo "| scene | majorant | median seconds (render) | time ratio global / local | image mean |"
echo "|---|---|---|---|---|"
for c in "${CASES[@]}"; do
  IFS='|' read -r NAME SCENE ARGS <<<"$c"
  : > "$OUT/${NAME}_local.t"; : > "$OUT/${NAME}_global.t"
  for i in $(seq "$REPEATS"); do
    for maj in local global; do
      # shellcheck disable=SC2086
      "$V" render "$SCENE" -o "$OUT/${NAME}_$maj.exr" -q --method reference --set render.majorant=$maj \
          --set render.max_depth=8 --seed 3 $ARGS --stats "$OUT/${NAME}_$maj.json"
      python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seconds']['render'])" "$OUT/${NAME}_$maj.json" >> "$OUT/${NAME}_$maj.t"
    done
  done
  tl=$(median < "$OUT/${NAME}_local.t"); tg=$(median < "$OUT/${NAME}_global.t")
  cmp=$("$V" compare "$OUT/${NAME}_global.exr" "$OUT/${NAME}_local.exr")
  mg=$(echo "$cmp" | awk '$1=="mean_test"{print $2}'); ml=$(echo "$cmp" | awk '$1=="mean_reference"{print $2}')
  printf "| %s | local | %.3f | | %.6g |\n| %s | global | %.3f | %.2f | %.6g |\n" "$NAME" "$tl" "$ml" "$NAME" "$tg" \
      "$(python3 -c "print($tg / $tl)")" "$mg"
done
