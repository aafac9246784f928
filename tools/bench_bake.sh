#!/usr/bin/env bash
# Photon tracing + cache build cost: `vdbmarch bake` on the paper-style glass
# scene and on the Disney cloud (when ../shared/assets is present), for three
# photon counts, three k and three qualities a. Prints a markdown table of
# median wall times over REPEATS runs (default 3), with the stage split and
# memory from --stats. Photons follow up to 8 scattering events
# (render.max_depth = 8), as a multiple-scattering photon map does.
# Usage: tools/bench_bake.sh [OUT_DIR] [REPEATS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/bench_out/bake}
repeats=${2:-3}
bin=$root/build/bin/vdbmarch
mkdir -p "$out"
scenes=("glass:$root/vdb_samples/glass.json")
cloud=$root/../shared/assets/wdas_cloud_sixteenth.vdb
if [ -f "$cloud" ]; then
  # The bare-.vdb scene (sun + sky) with forward scattering and multiple scattering.
  "$bin" render "$cloud" -o "$out/cloud_probe.exr" --res 8x6 --save-scene "$out/cloud.json" -q
  python3 - "$out/cloud.json" "$cloud" <<'PY'
import json, sys
p = sys.argv[1]; s = json.load(open(p))
s["media"][0]["g"] = 0.8
s["media"][0]["file"] = sys.argv[2]
json.dump(s, open(p, "w"), indent=2)
PY
  scenes+=("cloud:$out/cloud.json")
fi
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
printf '| scene | photons N | k | a | photons stored | cells | trace s | kd-tree s | cache s | total s | bytes/photon | bytes/cell |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|\n'
run() {  # scene-name scene-file N k a
  local name=$1 file=$2 n=$3 k=$4 a=$5 totals=()
  for r in $(seq "$repeats"); do
    "$bin" bake "$file" -o "$out/c.vdb" --photons "$n" --k "$k" --quality "$a" --stats "$out/s.json" -q \
      --set render.max_depth=8
    totals+=("$(python3 -c "import json;print(json.load(open('$out/s.json'))['seconds']['total'])")")
    cp "$out/s.json" "$out/s_$r.json"
  done
  local med
  med=$(printf '%s\n' "${totals[@]}" | median)
  # Report the stage split of the run whose total is the median.
  for r in $(seq "$repeats"); do
    if python3 -c "import json,sys;sys.exit(0 if abs(json.load(open('$out/s_$r.json'))['seconds']['total']-$med)<1e-12 else 1)"; then
      python3 - "$out/s_$r.json" "$name" "$n" "$k" "$a" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = s["seconds"]; b = s["bytes"]
print(f"| {sys.argv[2]} | {int(sys.argv[3]):,} | {sys.argv[4]} | {sys.argv[5]} | {s['photons']:,} | {s['cells']:,} | "
      f"{t['trace']:.3f} | {t['kd_tree']:.3f} | {t['topology']+t['estimate']:.3f} | {t['total']:.3f} | "
      f"{b['photon_map']/max(1,s['photons']):.1f} | {b['cache']/max(1,s['cells']):.1f} |")
PY
      break
    fi
  done
}
for entry in "${scenes[@]}"; do
  name=${entry%%:*} file=${entry#*:}
  for n in 100000 300000 1000000; do run "$name" "$file" "$n" 50 1; done
  for k in 25 100; do run "$name" "$file" 300000 "$k" 1; done
  for a in 0.5 2; do run "$name" "$file" 300000 50 "$a"; done
done
