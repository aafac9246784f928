#!/usr/bin/env bash
# Equal-time comparison of the three marchers on the paper's scenes
# (vdb_samples/scenes): vdbmarch bench with time budgets (photon tracing and
# cache building count in each method's time), error against a reference, an
# image strip per scene. Usage: tools/bench_marchers.sh [OUT] [SCENE...]
# Environment: RES (default 80x60), BUDGETS (seconds, default 2,4,8,16).
#
# Reference: the transmittance marcher at 1024 samples per pixel (another
# pixel seed, the same photon seed). It has the same expectation as the three
# methods (the same L_i estimate: with the default render.li = "path",
# shadow rays and continuation paths, and photons only for the caustics of
# delta lights through refracting glass, which no path finds; those photons
# are the same map, so their kNN blur is common to all), so the tables
# measure what the methods differ in, their sampling noise at equal time.
# Against the full truth, use tools/bench_yardstick.sh or vdbmarch bench
# with a converged path-traced reference (BENCHMARKS.md); where a delta
# light is seen through glass (exp1_point, exp2_collimated, fig4_caustic) the
# path tracer cannot converge at all.
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

# The scene's photon seed (render.seed unless photons.seed is set): the
# reference shares the methods' caustic photon map, whose noise pattern no
# number of samples per pixel averages out, and differs only in its pixel
# samples.
photonSeed() {
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d.get("photons",{}).get("seed", d.get("render",{}).get("seed",0)))' "$1"
}

marcherReference() {  # name scene spp: a transmittance image at many samples
  local name=$1 scene=$2 spp=$3
  mkdir -p "$OUT/$name"
  [ -f "$OUT/$name/reference_transmittance.exr" ] ||
    "$V" render "$scene" -o "$OUT/$name/reference_transmittance.exr" --method transmittance --spp "$spp" \
        --res "$RES" --seed 977 --set "photons.seed=$(photonSeed "$scene")" -q
}

want() { [ $# -eq 0 ] || [[ " $* " == *" $NAME "* ]]; }

for NAME in fig3b fig4 exp1_point exp2 exp1_sphere cloud; do
  want "$@" || continue
  case $NAME in
    fig3b) SCENE="$S/fig3b_spots.json" ;;
    fig4) SCENE="$S/fig4_caustic.json" ;;
    exp1_point) SCENE="$S/exp1_point.json" ;;
    exp2) SCENE="$S/exp2_collimated.json" ;;
    exp1_sphere) SCENE="$S/exp1_sphere.json" ;;
    cloud)
      SCENE="$S/cloud_sun.json"
      if [ ! -d "$ROOT/../shared/assets" ]; then
        echo "bench_marchers: ../shared/assets is absent: cloud skipped" >&2
        continue
      fi ;;
  esac
  marcherReference "$NAME" "$SCENE" "${REFERENCE_SPP:-1024}"
  bench "$NAME" "$SCENE" --reference "$OUT/$NAME/reference_transmittance.exr"
done
