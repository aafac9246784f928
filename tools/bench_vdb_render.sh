#!/usr/bin/env bash
# vdbmarch's uniform marcher against OpenVDB's vdb_render on the same physics:
# single scattering, one directional light, isotropic phase, no shadow-ray
# gain, tiny cutoff, step = shadow step = 1 voxel, same camera, 1 ray per pixel
# centre. The converged answer is vdb_render at step = shadow step = 0.25
# voxel (cached in OUT_DIR: it takes minutes).
#
# usage: tools/bench_vdb_render.sh [OUT_DIR] [REPEATS]
# Conventions (bench/vdb_render_notes.md): vdb_render's -step and -scatter are
# per voxel, -fov is horizontal, -light X,Y,Z points towards the light and its
# colour is L_i without the 1/(4 pi) of the phase function. So
#   sigma_s = scatter / h, sigma_a = absorb / h, irradiance = 4 pi * colour.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/bench_out/vdb_render}"
REPEATS="${2:-3}"
VDBMARCH="$ROOT/build/bin/vdbmarch"
ASSETS="$ROOT/../shared/assets"
mkdir -p "$OUT"
command -v vdb_render >/dev/null || { echo "vdb_render not found (Debian package libopenvdb-tools)" >&2; exit 1; }

# name vdb voxel_size res_w res_h cam_pos look_at hfov_deg scatter absorb light_towards
CASES=()
if [ -f "$ASSETS/wdas_cloud_sixteenth.vdb" ]; then
  CASES+=("disney_cloud|$ASSETS/wdas_cloud_sixteenth.vdb|3.33333325|640|480|253,223,758|-11.67,50,-45|40|0.2|0.01|1,0.7,-0.4")
else
  echo "note: $ASSETS/wdas_cloud_sixteenth.vdb absent: skipping the Disney cloud" >&2
fi
CASES+=("sample_cloud|$ROOT/vdb_samples/cloud.vdb|0.016|640|480|1.47,0.88,3.25|0,0.17,0|45.4|0.096|0.0048|-0.55,0.75,0.35")

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
now() { date +%s.%N; }

echo "| scene | renderer | step (voxels) | median seconds | RMSE | RMSE / mean | ratio to vdb_render (time) |"
echo "|---|---|---|---|---|---|---|"
for c in "${CASES[@]}"; do
  IFS='|' read -r NAME VDB H W HH POS LOOK HFOV SC AB LT <<<"$c"
  common=(-res "${W}x${HH}" -translate "$POS" -lookat "$LOOK" -up 0,1,0 -fov "$HFOV" -gain 0 -cutoff 1e-10
          -scatter "$SC,$SC,$SC" -absorb "$AB,$AB,$AB" -light "$LT,1,1,1" -compression none -cpus 0)
  REF="$OUT/${NAME}_vdb_render_step0.25.exr"
  if [ ! -f "$REF" ]; then
    echo "rendering the converged reference for $NAME (vdb_render step 0.25; minutes)..." >&2
    vdb_render "$VDB" "$REF.tmp.exr" "${common[@]}" -step 0.25 -shadowstep 0.25
    mv "$REF.tmp.exr" "$REF"
  fi
  # Our scene with the same physics.
  python3 - "$OUT/$NAME.json" "$VDB" "$H" "$W" "$HH" "$POS" "$LOOK" "$HFOV" "$SC" "$AB" "$LT" <<'PY'
import json, math, sys
out, vdb, h, w, hh, pos, look, hfov, sc, ab, lt = sys.argv[1:]
h = float(h); w = int(w); hh = int(hh)
vfov = 2 * math.degrees(math.atan(math.tan(math.radians(float(hfov)) / 2) * hh / w))
l = [float(x) for x in lt.split(',')]; n = math.sqrt(sum(x * x for x in l))
scene = {
  "camera": {"type": "perspective", "position": [float(x) for x in pos.split(',')],
             "look_at": [float(x) for x in look.split(',')], "up": [0, 1, 0],
             "fov_deg": vfov, "resolution": [w, hh]},
  "lights": [{"type": "directional", "direction": [-x / n for x in l],
              "irradiance": [4 * math.pi] * 3}],
  "media": [{"name": "volume", "type": "vdb", "file": vdb, "sigma_s": [float(sc) / h] * 3,
             "sigma_a": [float(ab) / h] * 3, "g": 0.0}],
  "background": [0, 0, 0],
  "render": {"method": "uniform", "spp": 1, "step": h, "shadow_step": h, "pixel_jitter": False, "seed": 7}}
json.dump(scene, open(out, "w"), indent=2)
PY
  # Alternate the two renderers so both see the same machine load.
  : > "$OUT/${NAME}_t_vdbr"; : > "$OUT/${NAME}_t_ours"
  for i in $(seq "$REPEATS"); do
    t0=$(now); vdb_render "$VDB" "$OUT/${NAME}_vdb_render_step1.exr" "${common[@]}" -step 1 -shadowstep 1; t1=$(now)
    echo "$t1 - $t0" | bc -l >> "$OUT/${NAME}_t_vdbr"
    t0=$(now); "$VDBMARCH" render "$OUT/$NAME.json" -o "$OUT/${NAME}_vdbmarch_step1.exr" -q --stats "$OUT/${NAME}_stats.json"; t1=$(now)
    echo "$t1 - $t0" | bc -l >> "$OUT/${NAME}_t_ours"
  done
  tv=$(median < "$OUT/${NAME}_t_vdbr"); to=$(median < "$OUT/${NAME}_t_ours")
  ev=$("$VDBMARCH" compare "$OUT/${NAME}_vdb_render_step1.exr" "$REF")
  eo=$("$VDBMARCH" compare "$OUT/${NAME}_vdbmarch_step1.exr" "$REF" --diff "$OUT/${NAME}_vdbmarch_diff.png")
  get() { echo "$1" | awk -v k="$2" '$1 == k {print $2}'; }
  printf "| %s | vdb_render | 1 | %.3f | %.5g | %.4f | 1 |\n" "$NAME" "$tv" "$(get "$ev" rmse)" "$(get "$ev" rmse_over_mean)"
  printf "| %s | vdbmarch uniform | 1 | %.3f | %.5g | %.4f | %.3f |\n" "$NAME" "$to" "$(get "$eo" rmse)" "$(get "$eo" rmse_over_mean)" "$(echo "$to / $tv" | bc -l)"
done
