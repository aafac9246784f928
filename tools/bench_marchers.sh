#!/usr/bin/env bash
# Equal-time comparison of the three marchers on the paper's scenes
# (vdb_samples/scenes): vdbmarch bench with time budgets (photon tracing and
# cache building count in each method's time), error against a reference, an
# image strip per scene. Usage: tools/bench_marchers.sh [OUT] [SCENE...]
# Environment: RES (default 80x60), BUDGETS (seconds, default 2,4,8,16).
#
# References: the path tracer where it converges (sphere lights, lights
# outside the medium); where a delta light is seen through glass
# (exp1_point, exp2_collimated) or a small light through a lens (fig4) it
# cannot converge, and the reference is the transmittance marcher at many
# samples (another seed): it has the same expectation as the three methods
# (the same L_i estimate), so those tables measure noise, not photon-map bias.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/bench_out/marchers}"
shift || true
RES="${RES:-80x60}"
BUDGETS="${BUDGETS:-2,4,8,16}"
V="$ROOT/build/bin/vdbmarch"
S="$ROOT/vdb_samples/scenes"
mkdir -p "$OUT"

bench() {  # name scene [bench options...]
  local name=$1 scene=$2
  shift 2
  "$V" bench "$scene" -o "$OUT/$name" --methods uniform,transmittance,guided --budgets "$BUDGETS" --seconds \
      --res "$RES" --strip "$OUT/$name/strip.png" "$@"
}

marcherReference() {  # name scene spp: a transmittance image at many samples
  local name=$1 scene=$2 spp=$3
  mkdir -p "$OUT/$name"
  [ -f "$OUT/$name/reference_transmittance.exr" ] ||
    "$V" render "$scene" -o "$OUT/$name/reference_transmittance.exr" --method transmittance --spp "$spp" \
        --res "$RES" --seed 977 -q
}

want() { [ $# -eq 0 ] || [[ " $* " == *" $NAME "* ]]; }

for NAME in fig3b fig4 exp1_sphere exp1_point exp2 cloud; do
  want "$@" || continue
  case $NAME in
    fig3b) bench fig3b "$S/fig3b_spots.json" --reference-spp 16384 ;;
    exp1_sphere) bench exp1_sphere "$S/exp1_sphere.json" --reference-spp 16384 ;;
    fig4) marcherReference fig4 "$S/fig4_caustic.json" 512
          bench fig4 "$S/fig4_caustic.json" --reference "$OUT/fig4/reference_transmittance.exr" ;;
    exp1_point) marcherReference exp1_point "$S/exp1_point.json" 512
          bench exp1_point "$S/exp1_point.json" --reference "$OUT/exp1_point/reference_transmittance.exr" ;;
    exp2) marcherReference exp2 "$S/exp2_collimated.json" 512
          bench exp2 "$S/exp2_collimated.json" --reference "$OUT/exp2/reference_transmittance.exr" ;;
    cloud)
      if [ -d "$ROOT/../shared/assets" ]; then
        bench cloud "$S/cloud_sun.json" --reference-spp 4096
      else
        echo "bench_marchers: ../shared/assets is absent: cloud skipped" >&2
      fi ;;
  esac
done
