#!/bin/bash
# Render a vdbmarch scene in pbrt-v4 as two independent halves and compare them with two halves of
# a vdbmarch truth (per-channel means, their ratio pbrt/vdbmarch, RMSE over the mean and how much of
# it the noise of the four renders explains).
# Usage: compare_truth.sh SCENE.json TRUTH_1.exr TRUTH_2.exr SPP_PER_HALF [W H]
# Env: PBRT_BUILD (/tmp/pbrt-v4-build), EXRSTAT (/tmp/pbrt_peer/exrstat), OUT (/tmp/pbrt_peer/compare),
#      THREADS (2), EXTRA (more converter options, e.g. "--max-depth 24").
set -euo pipefail
J=$1; T1=$2; T2=$3; SPP=$4; W=${5:-160}; H=${6:-120}
B=${PBRT_BUILD:-/tmp/pbrt-v4-build}; E=${EXRSTAT:-/tmp/pbrt_peer/exrstat}
O=${OUT:-/tmp/pbrt_peer/compare}; mkdir -p "$O"
HERE=$(cd "$(dirname "$0")" && pwd)
n=$(basename "$J" .json)
for h in 1 2; do
  python3 "$HERE/vdbmarch_to_pbrt.py" "$J" "$O/${n}_pbrt_$h.pbrt" --resolution "$W" "$H" --spp "$SPP" \
      --seed "30$h" ${EXTRA:-}
  s=$(date +%s)
  nice -n 19 "$B/pbrt" --nthreads "${THREADS:-2}" --quiet "$O/${n}_pbrt_$h.pbrt"
  echo "$n: pbrt half $h, $SPP spp, $(( $(date +%s) - s )) s"
done
"$E" cmp "$O/${n}_pbrt_1.exr" "$O/${n}_pbrt_2.exr" "$T1" "$T2"
