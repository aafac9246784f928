#!/usr/bin/env bash
# Run time of two vdbmarch binaries on the same fixed-sample renders, for a
# change whose pixels are bit-identical (tools/check_pixels.sh): then equal
# run time means equal error at equal time. Each scene renders with the
# default method at 160x120 on 2 threads, the two binaries alternating,
# RUNS times each; prints the medians of the whole run's seconds and their
# ratio (new / base).
# Usage: tools/bench_run_time.sh BASE_VDBMARCH NEW_VDBMARCH   (RUNS=3)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BASE="$1"; NEW="$2"; RUNS="${RUNS:-3}"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
seconds() {  # binary scene spp
  local t0 t1
  t0=$(date +%s.%N)
  "$1" render "$2" -o "$OUT/o.exr" --res 160x120 --spp "$3" --threads 2 --method auto -q --no-denoise
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc
}
printf '%-22s %5s %8s %8s %7s\n' scene spp base new ratio
for entry in cloud:128 cloud_sky:64 glass:16 plume:64 scenes/fig3b_spots:96 scenes/exp1_point:8 scenes/exp1_sphere:16 \
             scenes/exp2_collimated:8 scenes/fig4_caustic:8 scenes/fig4_caustic_sphere:64 scenes/cloud_sun:64; do
  scene="${entry%%:*}"; spp="${entry##*:}"
  if [ "$scene" = scenes/cloud_sun ] && [ ! -d "$ROOT/../shared/assets" ]; then continue; fi
  : > "$OUT/base"; : > "$OUT/new"
  for _ in $(seq "$RUNS"); do
    seconds "$BASE" "$ROOT/vdb_samples/$scene.json" "$spp" >> "$OUT/base"
    seconds "$NEW" "$ROOT/vdb_samples/$scene.json" "$spp" >> "$OUT/new"
  done
  b=$(median < "$OUT/base"); n=$(median < "$OUT/new")
  printf '%-22s %5s %8.3f %8.3f %7.3f\n' "$(basename "$scene")" "$spp" "$b" "$n" "$(echo "$n / $b" | bc -l)"
done
